#pragma once
// A loopback TCP proxy between a daemon and the throw-away PostgreSQL that
// can be told to go silent: it then forwards nothing in either direction and
// accepts nothing, but closes nothing, as a hub behind a pulled cable or a
// PC that froze looks to its clients (the kernel keeps the connections
// open: this end still acknowledges). Told to forward again, it goes on
// with what waited.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <utility>
#include <vector>

namespace shoptest {

class SilentProxy {
 public:
  explicit SilentProxy(unsigned short upstream_port) : upstream_(upstream_port) {
    listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    const int one = 1;
    ::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = 0;
    if (::bind(listen_fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(listen_fd_, 64) != 0)
      throw std::runtime_error("silent proxy: cannot listen");
    socklen_t len = sizeof a;
    ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&a), &len);
    port_ = ntohs(a.sin_port);
    thread_ = std::thread([this] { run(); });
  }
  ~SilentProxy() {
    stop_ = true;
    thread_.join();
    for (auto& [c, u] : pairs_) {
      ::close(c);
      ::close(u);
    }
    ::close(listen_fd_);
  }
  SilentProxy(const SilentProxy&) = delete;
  SilentProxy& operator=(const SilentProxy&) = delete;

  unsigned short port() const { return port_; }
  void set_silent(bool s) { silent_ = s; }

 private:
  int connect_upstream() const {
    const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(upstream_);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
      ::close(fd);
      return -1;
    }
    return fd;
  }

  // Copies what `from` holds to `to`; false when either end closed.
  static bool pump(int from, int to) {
    char buf[16384];
    const auto n = ::read(from, buf, sizeof buf);
    if (n <= 0) return false;
    for (ssize_t off = 0; off < n;) {
      const auto w = ::write(to, buf + off, static_cast<std::size_t>(n - off));
      if (w <= 0) return false;
      off += w;
    }
    return true;
  }

  void run() {
    while (!stop_) {
      if (silent_) {  // nothing read, nothing accepted, nothing closed
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        continue;
      }
      std::vector<pollfd> fds = {{listen_fd_, POLLIN, 0}};
      for (const auto& [c, u] : pairs_) {
        fds.push_back({c, POLLIN, 0});
        fds.push_back({u, POLLIN, 0});
      }
      if (::poll(fds.data(), fds.size(), 10) <= 0) continue;
      if (silent_) continue;
      if (fds[0].revents & POLLIN) {
        const int c = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
        if (c >= 0) {
          const int u = connect_upstream();
          if (u < 0) ::close(c);
          else pairs_.emplace_back(c, u);
        }
      }
      std::vector<std::size_t> closed;
      for (std::size_t i = 0; i < (fds.size() - 1) / 2; ++i) {  // the pairs polled (not one accepted just now)
        const auto& cf = fds[1 + 2 * i];
        const auto& uf = fds[2 + 2 * i];
        bool ok = true;
        if (cf.revents) ok = pump(cf.fd, uf.fd);
        if (ok && uf.revents) ok = pump(uf.fd, cf.fd);
        if (!ok) closed.push_back(i);
      }
      for (auto it = closed.rbegin(); it != closed.rend(); ++it) {
        ::close(pairs_[*it].first);
        ::close(pairs_[*it].second);
        pairs_.erase(pairs_.begin() + static_cast<std::ptrdiff_t>(*it));
      }
    }
  }

  unsigned short upstream_;
  unsigned short port_ = 0;
  int listen_fd_ = -1;
  std::vector<std::pair<int, int>> pairs_;  // client, upstream (the proxy's thread only)
  std::atomic<bool> silent_{false};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace shoptest
