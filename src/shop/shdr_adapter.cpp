#include "cncstream/shop/shdr_adapter.hpp"

#include <boost/asio/read_until.hpp>
#include <boost/asio/streambuf.hpp>
#include <boost/asio/write.hpp>
#include <fmt/format.h>

#include <deque>
#include <istream>

#include "cncstream/transport/journal.hpp"

namespace cncstream::shop {

namespace detail_shdr {

// SHDR values are separated by '|': a value never carries one, nor a line break.
std::string clean(const std::string& v) {
  std::string out = v;
  for (auto& c : out)
    if (c == '|' || c == '\n' || c == '\r') c = ' ';
  return out;
}

std::string number(const std::optional<double>& v) { return v ? fmt::format("{:.3f}", *v) : "UNAVAILABLE"; }

}  // namespace detail_shdr

std::string shdr_lines(const std::string& ts, const MachineState& s, const MachineState* prev) {
  using detail_shdr::clean;
  using detail_shdr::number;
  std::string items;
  const auto item = [&](const char* key, const std::string& v, bool changed) {
    if (prev && !changed) return;
    items += fmt::format("|{}|{}", key, v);
  };
  item("avail", s.availability, prev && prev->availability != s.availability);
  item("execution", s.availability == "AVAILABLE" ? s.execution : "UNAVAILABLE",
       prev && (prev->execution != s.execution || prev->availability != s.availability));
  item("mode", s.controller_mode, prev && prev->controller_mode != s.controller_mode);
  item("program", s.program.empty() ? "UNAVAILABLE" : clean(s.program), prev && prev->program != s.program);
  item("line", std::to_string(s.line), prev && prev->line != s.line);
  const std::string pos = s.path_position ? fmt::format("{:.3f} {:.3f} {:.3f}", (*s.path_position)[0],
                                                        (*s.path_position)[1], (*s.path_position)[2])
                                          : "UNAVAILABLE";
  item("path_pos", pos, prev && prev->path_position != s.path_position);
  item("path_feedrate", number(s.path_feedrate), prev && prev->path_feedrate != s.path_feedrate);
  item("feed_ovr", number(s.feed_override), prev && prev->feed_override != s.feed_override);
  std::string out;
  if (!items.empty()) out = ts + items + "\n";
  // A condition goes on a line of its own.
  if (!prev || prev->alarm != s.alarm) {
    if (s.alarm.empty()) out += ts + "|system|NORMAL||||\n";
    else {
      std::string code = s.alarm;
      if (const auto sp = code.find(' '); sp != std::string::npos) code.resize(sp);
      out += ts + "|system|FAULT|" + clean(code) + "|||" + clean(s.alarm) + "\n";
    }
  }
  return out;
}

struct ShdrAdapter::Client {
  explicit Client(boost::asio::io_context& io) : socket(io) {}
  boost::asio::ip::tcp::socket socket;
  boost::asio::streambuf in;
  std::deque<std::string> out;
  bool writing = false;
};

ShdrAdapter::ShdrAdapter(boost::asio::io_context& io, const std::string& address, unsigned short port,
                         std::string machine)
    : io_(io), acceptor_(io), machine_(std::move(machine)) {
  boost::system::error_code ec;
  const auto addr = boost::asio::ip::make_address(address, ec);
  if (ec) throw std::runtime_error("MTConnect adapter for " + machine_ + ": bad address '" + address + "'");
  const boost::asio::ip::tcp::endpoint ep(addr, port);
  acceptor_.open(ep.protocol(), ec);
  if (!ec) acceptor_.set_option(boost::asio::socket_base::reuse_address(true), ec);
  if (!ec) acceptor_.bind(ep, ec);
  if (!ec) acceptor_.listen(16, ec);
  if (ec)
    throw std::runtime_error(fmt::format("MTConnect adapter for {}: cannot listen on {}:{}: {}", machine_, address,
                                         port, ec.message()));
  accept();
}

ShdrAdapter::~ShdrAdapter() {
  *alive_ = false;
  boost::system::error_code ec;
  acceptor_.close(ec);
  for (auto& c : clients_) c->socket.close(ec);
}

unsigned short ShdrAdapter::port() const { return acceptor_.local_endpoint().port(); }

void ShdrAdapter::accept() {
  auto c = std::make_shared<Client>(io_);
  acceptor_.async_accept(c->socket, [this, c, alive = alive_](const boost::system::error_code& ec) {
    if (!*alive || ec == boost::asio::error::operation_aborted) return;
    if (!ec) {
      clients_.push_back(c);
      send(c, shdr_lines(transport::Journal::now_iso8601(), state_, nullptr));
      read(c);
    }
    accept();
  });
}

void ShdrAdapter::read(const std::shared_ptr<Client>& c) {
  boost::asio::async_read_until(c->socket, c->in, '\n',
                                [this, c, alive = alive_](const boost::system::error_code& ec, std::size_t) {
                                  if (!*alive) return;
                                  if (ec) return drop(c);
                                  std::istream is(&c->in);
                                  std::string line;
                                  std::getline(is, line);
                                  if (!line.empty() && line.back() == '\r') line.pop_back();
                                  // The agent's heartbeat: answered with ours (ms it may wait for the next).
                                  if (line.starts_with("* PING")) send(c, "* PONG 10000\n");
                                  if (c->in.size() > 4096) return drop(c);  // not an agent
                                  read(c);
                                });
}

void ShdrAdapter::send(const std::shared_ptr<Client>& c, std::string text) {
  if (text.empty()) return;
  if (c->out.size() > 1000) return drop(c);  // a client that does not read
  c->out.push_back(std::move(text));
  if (!c->writing) flush(c);
}

void ShdrAdapter::flush(const std::shared_ptr<Client>& c) {
  if (c->out.empty()) {
    c->writing = false;
    return;
  }
  c->writing = true;
  boost::asio::async_write(c->socket, boost::asio::buffer(c->out.front()),
                           [this, c, alive = alive_](const boost::system::error_code& ec, std::size_t) {
                             if (!*alive) return;
                             if (ec) return drop(c);
                             c->out.pop_front();
                             flush(c);
                           });
}

void ShdrAdapter::drop(const std::shared_ptr<Client>& c) {
  boost::system::error_code ec;
  c->socket.close(ec);
  clients_.remove(c);
}

void ShdrAdapter::update(const MachineState& s) {
  const std::string lines = shdr_lines(transport::Journal::now_iso8601(), s, &state_);
  state_ = s;
  if (lines.empty()) return;
  for (auto& c : std::list<std::shared_ptr<Client>>(clients_)) send(c, lines);
}

}  // namespace cncstream::shop
