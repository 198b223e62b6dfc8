#pragma once
// The HTTP/1.1 + WebSocket server (Boost.Beast, in http_server.cpp only):
// one session object per connection, reading the header first (with its own
// time-out), checking it, then reading the body into memory (JSON, bounded)
// or into a temporary file (uploads, bounded, with a body time-out). A cap
// on connections; WebSocket sessions write their client's coalesced queue.
#include <boost/asio/io_context.hpp>

#include <memory>

#include "cncstream/daemon/api.hpp"

namespace cncstream::daemon {

class HttpServer {
 public:
  HttpServer(boost::asio::io_context& io, const DaemonConfig& config, Api& api, FileStore& files);
  ~HttpServer();
  // Binds and listens; throws std::runtime_error naming the address.
  void start();
  void stop();
  unsigned short port() const;  // the bound port (config port 0: chosen by the kernel)
  std::size_t connections() const;

  struct Impl;  // the acceptor and what its connections share (http_server.cpp)

 private:
  std::shared_ptr<Impl> impl_;
};

}  // namespace cncstream::daemon
