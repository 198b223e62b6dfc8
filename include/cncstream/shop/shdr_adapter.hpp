#pragma once
// An MTConnect adapter (SHDR over TCP, docs/shop.md) for one machine: an
// agent or dashboard connects, gets every data item, then each change as
// `timestamp|key|value|...`; `* PING` is answered `* PONG <ms>`. Data
// items: avail, execution, mode, program, line, path_pos, path_feedrate,
// feed_ovr and the condition `system` (FAULT with the alarm). Loopback by
// default. Runs on the daemon's event loop (Boost.Asio).
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>

#include <list>
#include <memory>
#include <string>

#include "cncstream/shop/machine_state.hpp"

namespace cncstream::shop {

// The SHDR lines for a state: all items (previous nullptr) or those changed.
std::string shdr_lines(const std::string& timestamp, const MachineState& now, const MachineState* previous);

class ShdrAdapter {
 public:
  // Listens at once; port 0: any free port. Throws naming the address on failure.
  ShdrAdapter(boost::asio::io_context& io, const std::string& address, unsigned short port, std::string machine);
  ~ShdrAdapter();
  ShdrAdapter(const ShdrAdapter&) = delete;
  ShdrAdapter& operator=(const ShdrAdapter&) = delete;
  unsigned short port() const;
  const std::string& machine() const { return machine_; }
  // The machine's state now (event loop thread): the changes go to every client.
  void update(const MachineState& s);

 private:
  struct Client;
  void accept();
  void read(const std::shared_ptr<Client>& c);
  void send(const std::shared_ptr<Client>& c, std::string text);
  void flush(const std::shared_ptr<Client>& c);
  void drop(const std::shared_ptr<Client>& c);
  boost::asio::io_context& io_;
  boost::asio::ip::tcp::acceptor acceptor_;
  std::string machine_;
  MachineState state_;
  std::list<std::shared_ptr<Client>> clients_;
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

}  // namespace cncstream::shop
