#include "cncstream/daemon/http_server.hpp"

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/strand.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <limits>

#include "http_request.hpp"

namespace cncstream::daemon {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = net::ip::tcp;

namespace {

std::chrono::steady_clock::duration seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
}

}  // namespace

struct HttpServer::Impl : std::enable_shared_from_this<HttpServer::Impl> {
  net::io_context& io;
  const DaemonConfig& config;
  Api& api;
  FileStore& files;
  tcp::acceptor acceptor;
  std::size_t connections = 0;
  bool stopped = false;

  Impl(net::io_context& io_, const DaemonConfig& c, Api& a, FileStore& f)
      : io(io_), config(c), api(a), files(f), acceptor(io_) {}
  void accept();
};

namespace {

// ---- WebSocket session ------------------------------------------------------

class WsSession : public WsPeer, public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(std::shared_ptr<HttpServer::Impl> server, tcp::socket&& socket)
      : server_(std::move(server)), ws_(std::move(socket)) {}
  ~WsSession() override { --server_->connections; }

  void run(const http::request<http::empty_body>& req, Request upgrade) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.read_message_max(std::size_t{64} * 1024);
    ws_.async_accept(req, [self = shared_from_this(), upgrade = std::move(upgrade)](beast::error_code ec) {
      if (ec) return;
      self->client_ = self->server_->api.ws_open(upgrade, self->weak_from_this());
      if (!self->client_) {
        self->ws_.async_close(websocket::close_reason(websocket::close_code::try_again_later, "too many clients"),
                              [self](beast::error_code) {});
        return;
      }
      self->read();
      self->kick();
    });
  }

  void kick() override {
    if (writing_ || closing_ || !client_) return;
    Frame f = client_->queue.pop();
    if (!f) return;
    writing_ = true;
    ws_.text(true);
    ws_.async_write(net::buffer(*f), [self = shared_from_this(), f](beast::error_code ec, std::size_t) {
      self->writing_ = false;
      if (ec) {
        self->gone();
        return;
      }
      self->kick();
    });
  }

  void close_slow(const std::string& why) override {
    if (closing_) return;
    closing_ = true;
    spdlog::warn("websocket client {}: dropped: {}", client_ ? client_->client_id : std::string("?"), why);
    gone();
    // Closing while a write is in flight is not allowed: cut the socket instead.
    beast::error_code ec;
    beast::get_lowest_layer(ws_).socket().shutdown(tcp::socket::shutdown_both, ec);
    beast::get_lowest_layer(ws_).socket().close(ec);
  }

 private:
  void read() {
    ws_.async_read(in_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) {
        self->gone();
        return;
      }
      const std::string text = beast::buffers_to_string(self->in_.data());
      self->in_.consume(self->in_.size());
      if (self->client_ && !self->closing_) self->server_->api.ws_message(*self->client_, text);
      self->read();
    });
  }
  void gone() {
    if (client_) {
      auto c = std::move(client_);
      server_->api.ws_close(*c);
    }
  }

  std::shared_ptr<HttpServer::Impl> server_;
  websocket::stream<beast::tcp_stream> ws_;
  beast::flat_buffer in_;
  std::shared_ptr<WsClient> client_;
  bool writing_ = false;
  bool closing_ = false;
};

// ---- HTTP session -----------------------------------------------------------

class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(std::shared_ptr<HttpServer::Impl> server, tcp::socket&& socket)
      : server_(std::move(server)), stream_(std::move(socket)), deadline_(stream_.get_executor()) {}
  ~HttpSession() {
    if (counted_) --server_->connections;
  }

  void run(bool over_cap) {
    counted_ = true;
    if (over_cap) {
      keep_alive_ = false;
      write(Response::error(503, "busy", "too many connections"), 11);
      return;
    }
    read_header();
  }

 private:
  // Reads time out by a timer of our own that cancels the read, so the
  // socket is still open to say 408 (a tcp_stream time-out closes it).
  void arm(double s) {
    timed_out_ = false;
    deadline_.expires_after(seconds(s));
    deadline_.async_wait([weak = weak_from_this()](beast::error_code ec) {
      if (ec) return;
      if (auto self = weak.lock()) {
        self->timed_out_ = true;
        beast::error_code ignored;
        self->stream_.socket().cancel(ignored);
      }
    });
  }
  void disarm() { deadline_.cancel(); }

  void read_header() {
    header_.emplace();
    header_->header_limit(kMaxHeaderBytes);
    // The body's size is checked by the body's own parser (JSON) or the
    // precheck (uploads), each answering 413. (Not boost::none: Beast 1.74
    // compares a Content-Length with the empty optional and always fails.)
    header_->body_limit(std::numeric_limits<std::uint64_t>::max());
    stream_.expires_never();
    arm(server_->config.limits.header_timeout_s);
    http::async_read_header(stream_, buffer_, *header_,
                            [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_header(ec); });
  }

  void on_header(beast::error_code ec) {
    disarm();
    if (timed_out_) {
      keep_alive_ = false;
      write(Response::error(408, "timeout", "the request's headers did not arrive in time"), 11);
      return;
    }
    if (ec == http::error::header_limit) {
      keep_alive_ = false;
      write(Response::error(431, "bad_request", "request headers too large"), 11);
      return;
    }
    if (ec) {
      spdlog::debug("connection: header not read: {}", ec.message());
      return close();
    }
    auto& h = header_->get();
    version_ = h.version();
    keep_alive_ = h.keep_alive();
    bool ok = false;
    req_ = request_from(h.base(), ok);
    if (!ok) {
      keep_alive_ = false;
      write(Response::error(400, "bad_request", "malformed request target"), version_);
      return;
    }
    const bool upgrade = websocket::is_upgrade(h);
    if (auto e = server_->api.precheck(req_, upgrade && req_.path == "/api/v1/ws")) {
      keep_alive_ = false;  // the body (if any) is not read: the connection cannot be reused
      write(std::move(*e), version_);
      return;
    }
    if (upgrade) {
      if (req_.path != "/api/v1/ws") {
        keep_alive_ = false;
        write(Response::error(404, "not_found", "no WebSocket at " + req_.path), version_);
        return;
      }
      auto ws = std::make_shared<WsSession>(server_, stream_.release_socket());
      ++server_->connections;  // the WebSocket session counts itself; this one is ending
      ws->run(header_->release(), std::move(req_));
      return;
    }
    arm(server_->config.limits.body_timeout_s);
    if (server_->api.is_upload(req_)) {
      upload_.emplace(std::move(*header_));
      upload_->body_limit(server_->config.limits.max_upload_bytes);
      temp_ = server_->files.temp_path();
      beast::error_code fec;
      upload_->get().body().open(temp_.c_str(), beast::file_mode::write, fec);
      if (fec) {
        keep_alive_ = false;
        write(Response::error(500, "internal", "cannot spool the upload: " + fec.message()), version_);
        return;
      }
      http::async_read(stream_, buffer_, *upload_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
        self->upload_->get().body().close();
        if (ec) return self->body_failed(ec);
        self->req_.body_file = self->temp_;
        self->req_.body_size = std::filesystem::file_size(self->temp_);
        self->temp_.clear();
        self->dispatch();
      });
      return;
    }
    body_.emplace(std::move(*header_));
    body_->body_limit(server_->config.limits.max_json_bytes);
    if (declared_beyond(body_->content_length(), server_->config.limits.max_json_bytes)) {
      disarm();
      keep_alive_ = false;  // the body is not read
      write(Response::error(413, "too_large", "the body exceeds the limit"), version_);
      return;
    }
    http::async_read(stream_, buffer_, *body_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) return self->body_failed(ec);
      self->req_.body = std::move(self->body_->get().body());
      self->dispatch();
    });
  }

  void body_failed(beast::error_code ec) {
    spdlog::debug("{} {}: body not read: {}", req_.method, req_.path, ec.message());
    disarm();
    drop_temp();
    keep_alive_ = false;
    if (timed_out_) return write(Response::error(408, "timeout", "the body did not arrive in time"), version_);
    if (ec == http::error::body_limit) return write(Response::error(413, "too_large", "the body exceeds the limit"), version_);
    close();
  }

  void dispatch() {
    disarm();  // a handler may take a while (upload hashing): no time-out while we work
    auto self = shared_from_this();
    auto strand_exec = stream_.get_executor();
    server_->api.handle(std::move(req_), [self, strand_exec](Response r) {
      net::post(strand_exec, [self, r = std::move(r)]() mutable { self->write(std::move(r), self->version_); });
    });
  }

  void write(Response r, unsigned version) {
    const auto status = static_cast<http::status>(r.status);
    auto finish = [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec || !self->keep_alive_) return self->close();
      self->req_ = Request{};
      self->read_header();
    };
    stream_.expires_after(seconds(server_->config.limits.body_timeout_s));
    if (!r.file.empty()) {
      http::response<http::file_body> res{status, version};
      beast::error_code ec;
      res.body().open(r.file.c_str(), beast::file_mode::scan, ec);
      if (ec) return write(Response::error(404, "not_found", "no such file"), version);
      fill(res, r);
      res.prepare_payload();
      auto sp = std::make_shared<http::response<http::file_body>>(std::move(res));
      http::async_write(stream_, *sp, [sp, finish](beast::error_code ec, std::size_t n) { finish(ec, n); });
      return;
    }
    http::response<http::string_body> res{status, version};
    res.body() = std::move(r.body);
    fill(res, r);
    res.prepare_payload();
    auto sp = std::make_shared<http::response<http::string_body>>(std::move(res));
    http::async_write(stream_, *sp, [sp, finish](beast::error_code ec, std::size_t n) { finish(ec, n); });
  }

  template <class Res>
  void fill(Res& res, const Response& r) {
    res.set(http::field::server, "cncstreamd");
    res.set(http::field::content_type, r.content_type);
    res.set("X-Content-Type-Options", "nosniff");
    res.set(http::field::cache_control, "no-store");
    for (const auto& [k, v] : r.headers) res.set(k, v);
    res.keep_alive(keep_alive_);
  }

  void drop_temp() {
    if (!temp_.empty()) {
      std::error_code ec;
      std::filesystem::remove(temp_, ec);
      temp_.clear();
    }
  }

  void close() {
    drop_temp();
    beast::error_code ec;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
    stream_.close();
  }

  std::shared_ptr<HttpServer::Impl> server_;
  beast::tcp_stream stream_;
  beast::flat_buffer buffer_{std::size_t{16} * 1024};
  std::optional<http::request_parser<http::empty_body>> header_;
  std::optional<http::request_parser<http::string_body>> body_;
  std::optional<http::request_parser<http::file_body>> upload_;
  net::steady_timer deadline_;
  bool timed_out_ = false;
  std::filesystem::path temp_;
  Request req_;
  unsigned version_ = 11;
  bool keep_alive_ = true;
  bool counted_ = false;
};

}  // namespace

void HttpServer::Impl::accept() {
  acceptor.async_accept(net::make_strand(io), [self = shared_from_this()](beast::error_code ec, tcp::socket socket) {
    if (self->stopped) return;
    if (!ec) {
      const bool over = self->connections >= self->config.limits.max_connections;
      ++self->connections;
      std::make_shared<HttpSession>(self, std::move(socket))->run(over);
    }
    self->accept();
  });
}

HttpServer::HttpServer(net::io_context& io, const DaemonConfig& config, Api& api, FileStore& files)
    : impl_(std::make_shared<Impl>(io, config, api, files)) {}

HttpServer::~HttpServer() { stop(); }

void HttpServer::start() {
  beast::error_code ec;
  const auto addr = net::ip::make_address(impl_->config.listen_address == "localhost" ? "127.0.0.1"
                                                                                        : impl_->config.listen_address,
                                          ec);
  if (ec) throw std::runtime_error("listen address '" + impl_->config.listen_address + "': " + ec.message());
  const tcp::endpoint ep{addr, impl_->config.listen_port};
  auto& a = impl_->acceptor;
  a.open(ep.protocol(), ec);
  if (!ec) a.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) a.bind(ep, ec);
  if (!ec) a.listen(net::socket_base::max_listen_connections, ec);
  if (ec) {
    throw std::runtime_error("cannot listen on " + impl_->config.listen_address + ":" +
                             std::to_string(impl_->config.listen_port) + ": " + ec.message());
  }
  impl_->accept();
}

void HttpServer::stop() {
  if (!impl_ || impl_->stopped) return;
  impl_->stopped = true;
  beast::error_code ec;
  impl_->acceptor.close(ec);
}

unsigned short HttpServer::port() const {
  beast::error_code ec;
  return impl_->acceptor.local_endpoint(ec).port();
}

std::size_t HttpServer::connections() const { return impl_->connections; }

}  // namespace cncstream::daemon
