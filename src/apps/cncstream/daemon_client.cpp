#include "daemon_client.hpp"

#include <fmt/core.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include <cctype>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <deque>
#include <limits>

namespace cncstream::app {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using Clock = std::chrono::steady_clock;

namespace {

Clock::time_point deadline_in(double seconds) {
  return Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

std::string seconds_text(double s) { return fmt::format("{:g} s", s); }

// Runs handlers until `done()` or the deadline; false on the deadline.
template <typename Done>
bool run_until(net::io_context& ioc, Done done, Clock::time_point deadline) {
  while (!done()) {
    const auto now = Clock::now();
    if (now >= deadline) return false;
    if (ioc.stopped()) ioc.restart();
    ioc.run_one_for(deadline - now);
  }
  return true;
}

}  // namespace

std::string DaemonAddress::url() const { return "http://" + host_header(); }

std::string DaemonAddress::host_header() const {
  return (host.find(':') != std::string::npos ? "[" + host + "]" : host) + ":" + port;
}

DaemonAddress parse_daemon_address(const std::string& text) {
  std::string rest = text;
  if (rest.rfind("https://", 0) == 0)
    throw std::invalid_argument("daemon address '" + text + "': https is not spoken; give http://HOST:PORT");
  if (rest.rfind("http://", 0) == 0) rest = rest.substr(7);
  if (const auto slash = rest.find('/'); slash != std::string::npos) rest = rest.substr(0, slash);
  DaemonAddress a;
  if (!rest.empty() && rest.front() == '[') {
    const auto close = rest.find(']');
    if (close == std::string::npos) throw std::invalid_argument("daemon address '" + text + "': unclosed '['");
    a.host = rest.substr(1, close - 1);
    rest = rest.substr(close + 1);
    if (!rest.empty() && rest.front() == ':') a.port = rest.substr(1);
  } else {
    const auto colon = rest.rfind(':');
    a.host = rest.substr(0, colon);
    if (colon != std::string::npos) a.port = rest.substr(colon + 1);
  }
  if (a.port.empty()) a.port = "8420";
  if (a.host.empty() || a.port.find_first_not_of("0123456789") != std::string::npos)
    throw std::invalid_argument("daemon address '" + text + "': expected http://HOST:PORT");
  return a;
}

std::string default_daemon_address() {
  const char* env = std::getenv("CNCSTREAM_DAEMON");
  return env && *env ? std::string(env) : std::string("http://127.0.0.1:8420");
}

std::string daemon_token_from_env() {
  const char* env = std::getenv("CNCSTREAM_TOKEN");
  return env ? std::string(env) : std::string();
}

std::string url_encode(const std::string& text) {
  std::string out;
  for (unsigned char c : text) {
    if (std::isalnum(c) || c == '-' || c == '.' || c == '_' || c == '~') {
      out.push_back(static_cast<char>(c));
    } else {
      out += fmt::format("%{:02X}", c);
    }
  }
  return out;
}

DaemonClient::DaemonClient(DaemonAddress address, std::string client_id, std::string token)
    : address_(std::move(address)), client_id_(std::move(client_id)), token_(std::move(token)) {}

HttpAnswer DaemonClient::request(const std::string& method, const std::string& target, const std::string& body,
                                 const std::string& content_type, double timeout_s) const {
  const std::string where = "the daemon at " + address_.url();
  net::io_context ioc;
  tcp::resolver resolver(ioc);
  beast::tcp_stream stream(ioc);
  beast::error_code ec;
  const auto endpoints = resolver.resolve(address_.host, address_.port, ec);
  if (ec) throw std::runtime_error("cannot reach " + where + ": " + ec.message());

  http::request<http::string_body> req{http::string_to_verb(method), target, 11};
  req.set(http::field::host, address_.host_header());
  req.set(http::field::user_agent, "cncstream");
  if (!client_id_.empty()) req.set("X-Client-Id", client_id_);
  if (!token_.empty()) req.set(http::field::authorization, "Bearer " + token_);
  if (method != "GET" && method != "DELETE") {
    req.set(http::field::content_type, content_type);
    req.body() = body;
  }
  req.keep_alive(false);
  req.prepare_payload();

  http::response_parser<http::string_body> parser;
  parser.body_limit(std::numeric_limits<std::uint64_t>::max());  // program downloads
  beast::flat_buffer buffer;
  beast::error_code result;
  bool done = false;
  const auto deadline = deadline_in(timeout_s);
  stream.expires_at(deadline);
  stream.async_connect(endpoints, [&](beast::error_code e, const tcp::endpoint&) {
    if (e) {
      result = e;
      done = true;
      return;
    }
    http::async_write(stream, req, [&](beast::error_code e2, std::size_t) {
      if (e2) {
        result = e2;
        done = true;
        return;
      }
      http::async_read(stream, buffer, parser, [&](beast::error_code e3, std::size_t) {
        result = e3;
        done = true;
      });
    });
  });
  ioc.run();
  if (!done || result == beast::error::timeout)
    throw std::runtime_error(where + " did not answer " + method + " " + target + " within " + seconds_text(timeout_s));
  if (result) throw std::runtime_error("cannot reach " + where + ": " + result.message());
  const auto& res = parser.get();
  HttpAnswer a;
  a.status = static_cast<int>(res.result_int());
  a.content_type = std::string(res[http::field::content_type]);
  a.body = res.body();
  return a;
}

nlohmann::json DaemonClient::json_of(const HttpAnswer& a, const std::string& what) const {
  if (a.status >= 200 && a.status < 300) {
    if (a.body.empty()) return nlohmann::json::object();
    auto j = nlohmann::json::parse(a.body, nullptr, false);
    if (j.is_discarded())
      throw std::runtime_error("the daemon at " + address_.url() + " answered " + what + " with something not JSON");
    return j;
  }
  const auto j = nlohmann::json::parse(a.body, nullptr, false);
  std::string code = "http_" + std::to_string(a.status);
  std::string message = a.body.empty() ? "HTTP " + std::to_string(a.status) : a.body;
  if (!j.is_discarded() && j.contains("error") && j["error"].is_object()) {
    code = j["error"].value("code", code);
    message = j["error"].value("message", message);
  }
  throw DaemonError(a.status, code, what + ": " + message);
}

nlohmann::json DaemonClient::get(const std::string& target, double timeout_s) const {
  return json_of(request("GET", target, {}, {}, timeout_s), "GET " + target);
}

nlohmann::json DaemonClient::post(const std::string& target, const nlohmann::json& body, double timeout_s) const {
  return json_of(request("POST", target, body.dump(), "application/json", timeout_s), "POST " + target);
}

nlohmann::json DaemonClient::del(const std::string& target, double timeout_s) const {
  return json_of(request("DELETE", target, {}, {}, timeout_s), "DELETE " + target);
}

nlohmann::json DaemonClient::upload(const std::string& target, const std::string& bytes, double timeout_s) const {
  return json_of(request("POST", target, bytes, "application/octet-stream", timeout_s), "upload");
}

std::string DaemonClient::get_text(const std::string& target, double timeout_s) const {
  const HttpAnswer a = request("GET", target, {}, {}, timeout_s);
  if (a.status >= 200 && a.status < 300) return a.body;
  json_of(a, "GET " + target);  // throws with the daemon's message
  return {};
}

// ---- WebSocket --------------------------------------------------------------

struct DaemonSocket::Impl {
  net::io_context ioc;
  websocket::stream<beast::tcp_stream> ws{ioc};
  beast::flat_buffer buffer;
  std::deque<nlohmann::json> inbox;
  std::string outgoing;  // the frame being written (must outlive the write)
  bool closed = false;
  std::string why;
  std::string url;

  void read_next() {
    ws.async_read(buffer, [this](beast::error_code ec, std::size_t) {
      if (ec) {
        closed = true;
        if (ec == websocket::error::closed) {
          const auto& r = ws.reason();
          why = "the daemon closed the connection";
          if (!r.reason.empty()) why.append(": ").append(r.reason.data(), r.reason.size());
        } else {
          why = ec.message();
        }
        return;
      }
      auto j = nlohmann::json::parse(beast::buffers_to_string(buffer.data()), nullptr, false);
      buffer.consume(buffer.size());
      if (j.is_object()) inbox.push_back(std::move(j));
      read_next();
    });
  }
};

DaemonSocket::DaemonSocket(const DaemonClient& client, double timeout_s) : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  const DaemonAddress& addr = client.address();
  s.url = addr.url();
  tcp::resolver resolver(s.ioc);
  beast::error_code ec;
  const auto endpoints = resolver.resolve(addr.host, addr.port, ec);
  if (ec) throw std::runtime_error("cannot reach the daemon at " + s.url + ": " + ec.message());
  const std::string& id = client.client_id();
  const std::string& token = client.token();
  // Non-browser clients send the long-lived token in the upgrade's header.
  s.ws.set_option(websocket::stream_base::decorator([id, token](websocket::request_type& req) {
    req.set(http::field::user_agent, "cncstream");
    if (!id.empty()) req.set("X-Client-Id", id);
    if (!token.empty()) req.set(http::field::authorization, "Bearer " + token);
  }));
  const std::string host = addr.host_header();
  const std::string target = "/api/v1/ws?client_id=" + url_encode(id);
  beast::error_code result;
  bool done = false;
  const auto deadline = deadline_in(timeout_s);
  auto& lowest = beast::get_lowest_layer(s.ws);
  lowest.expires_at(deadline);
  lowest.async_connect(endpoints, [&](beast::error_code e, const tcp::endpoint&) {
    if (e) {
      result = e;
      done = true;
      return;
    }
    s.ws.async_handshake(host, target, [&](beast::error_code e2) {
      result = e2;
      done = true;
    });
  });
  if (!run_until(s.ioc, [&] { return done; }, deadline + std::chrono::milliseconds(100)) ||
      result == beast::error::timeout)
    throw std::runtime_error("the daemon at " + s.url + " did not open its WebSocket within " + seconds_text(timeout_s));
  if (result) throw std::runtime_error("cannot open the daemon's WebSocket at " + s.url + ": " + result.message());
  lowest.expires_never();  // from here the WebSocket's own time-outs apply
  s.ws.set_option(websocket::stream_base::timeout::suggested(beast::role_type::client));
  s.ws.text(true);
  s.read_next();
}

DaemonSocket::~DaemonSocket() {
  Impl& s = *impl_;
  if (s.closed) return;
  // A polite close, briefly: the daemon releases this client's control and jogs on close.
  // If it fails (it may throw, and a destructor must not), the daemon sees
  // the connection drop, which releases them too.
  try {
    bool done = false;
    s.ws.async_close(websocket::close_code::normal, [&](beast::error_code) { done = true; });
    run_until(s.ioc, [&] { return done || s.closed; }, deadline_in(0.5));
  } catch (...) {
    // the connection is dropped instead
  }
}

void DaemonSocket::send(const nlohmann::json& message, double timeout_s) {
  Impl& s = *impl_;
  if (s.closed) throw std::runtime_error("the daemon's WebSocket at " + s.url + " is closed: " + s.why);
  s.outgoing = message.dump();
  bool done = false;
  beast::error_code result;
  s.ws.async_write(net::buffer(s.outgoing), [&](beast::error_code e, std::size_t) {
    result = e;
    done = true;
  });
  if (!run_until(s.ioc, [&] { return done; }, deadline_in(timeout_s))) {
    s.closed = true;
    s.why = "a message could not be sent within " + seconds_text(timeout_s);
    beast::get_lowest_layer(s.ws).close();  // the pending write ends with an error; nothing else is sent
    run_until(s.ioc, [&] { return done; }, deadline_in(1));
    throw std::runtime_error("the daemon's WebSocket at " + s.url + ": " + s.why);
  }
  if (result) {
    s.closed = true;
    s.why = result.message();
    throw std::runtime_error("the daemon's WebSocket at " + s.url + ": " + s.why);
  }
}

std::optional<nlohmann::json> DaemonSocket::read(double timeout_s) {
  Impl& s = *impl_;
  run_until(s.ioc, [&] { return !s.inbox.empty() || s.closed; }, deadline_in(timeout_s));
  if (!s.inbox.empty()) {
    nlohmann::json j = std::move(s.inbox.front());
    s.inbox.pop_front();
    return j;
  }
  if (s.closed) throw std::runtime_error("the daemon's WebSocket at " + s.url + " is closed: " + s.why);
  return std::nullopt;
}

double num_or(const nlohmann::json& j, const char* key, double fallback) {
  if (!j.is_object()) return fallback;
  const auto it = j.find(key);
  return it != j.end() && it->is_number() ? it->get<double>() : fallback;
}

std::string str_or(const nlohmann::json& j, const char* key, const std::string& fallback) {
  if (!j.is_object()) return fallback;
  const auto it = j.find(key);
  return it != j.end() && it->is_string() ? it->get<std::string>() : fallback;
}

nlohmann::json obj_or(const nlohmann::json& j, const char* key) {
  if (!j.is_object()) return nlohmann::json::object();
  const auto it = j.find(key);
  return it != j.end() && it->is_object() ? *it : nlohmann::json::object();
}

bool job_state_is_final(const std::string& s) {
  return s == "done" || s == "failed" || s == "stopped" || s == "interrupted" || s == "cancelled";
}

}  // namespace cncstream::app
