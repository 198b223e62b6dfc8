#pragma once
// Test helpers for the daemon: a daemon on a loopback port (port 0) running
// on its own thread, a tiny blocking HTTP/1.1 client and a tiny WebSocket
// client over POSIX sockets (no Beast in the tests: it is slow to compile),
// and waiting for conditions with deadlines.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <utility>

#include "cncstream/daemon/daemon.hpp"
#include "../support/loopback_http.hpp"

namespace dtest {

using namespace loopback;
using nlohmann::json;
namespace fs = std::filesystem;

inline fs::path temp_dir(const std::string& tag) {
  std::random_device rd;
  const fs::path p = fs::temp_directory_path() / ("cncstreamd-test-" + tag + "-" + std::to_string(::getpid()) + "-" +
                                                  std::to_string(rd()));
  fs::create_directories(p);
  return p;
}

inline bool wait_for(const std::function<bool()>& pred, double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < end) {
    if (pred()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return pred();
}

class WsClient {
 public:
  ~WsClient() { close(); }
  // Returns the HTTP status of the upgrade (101 on success).
  int connect(unsigned short port, const std::string& target, std::map<std::string, std::string> headers = {}) {
    fd_ = connect_to(port);
    if (fd_ < 0) return 0;
    std::string req = "GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) +
                      "\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
                      "Sec-WebSocket-Version: 13\r\n";
    for (auto& [k, v] : headers) req += k + ": " + v + "\r\n";
    req += "\r\n";
    send_all(fd_, req);
    // Read the response header byte by byte up to the blank line (frames may follow).
    std::string h;
    while (h.find("\r\n\r\n") == std::string::npos) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 5000) <= 0) return 0;
      char c;
      if (::recv(fd_, &c, 1, 0) != 1) break;
      h.push_back(c);
    }
    return h.size() >= 12 ? std::atoi(h.substr(9, 3).c_str()) : 0;
  }
  bool send(const std::string& text) {
    std::string f;
    f.push_back(static_cast<char>(0x81));
    const std::size_t n = text.size();
    if (n < 126) {
      f.push_back(static_cast<char>(0x80 | n));
    } else {
      f.push_back(static_cast<char>(0x80 | 126));
      f.push_back(static_cast<char>((n >> 8) & 0xff));
      f.push_back(static_cast<char>(n & 0xff));
    }
    const unsigned char mask[4] = {0x12, 0x34, 0x56, 0x78};
    f.append(reinterpret_cast<const char*>(mask), 4);
    for (std::size_t i = 0; i < n; ++i) f.push_back(static_cast<char>(text[i] ^ mask[i % 4]));
    return send_all(fd_, f);
  }
  bool send(const json& j) { return send(j.dump()); }
  // The next text message; nullopt on timeout or close.
  std::optional<std::string> recv(double timeout_s) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (true) {
      if (auto m = take_frame()) return m;
      if (closed_) return std::nullopt;
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(end - std::chrono::steady_clock::now()).count();
      if (left <= 0) return std::nullopt;
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left)) <= 0) return std::nullopt;
      char buf[65536];
      const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
      if (n <= 0) {
        closed_ = true;
        return std::nullopt;
      }
      in_.append(buf, static_cast<std::size_t>(n));
    }
  }
  // Waits for a message satisfying `pred` (others are skipped).
  std::optional<json> wait_message(const std::function<bool(const json&)>& pred, double timeout_s) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (true) {
      const double left = std::chrono::duration<double>(end - std::chrono::steady_clock::now()).count();
      if (left <= 0) return std::nullopt;
      const auto m = recv(left);
      if (!m) return std::nullopt;
      const json j = json::parse(*m);
      if (pred(j)) return j;
    }
  }
  bool closed() const { return closed_; }
  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }
  int fd() const { return fd_; }

 private:
  std::optional<std::string> take_frame() {
    while (true) {
      if (in_.size() < 2) return std::nullopt;
      const auto b0 = static_cast<unsigned char>(in_[0]), b1 = static_cast<unsigned char>(in_[1]);
      std::size_t len = b1 & 0x7f, off = 2;
      if (len == 126) {
        if (in_.size() < 4) return std::nullopt;
        len = (std::size_t(static_cast<unsigned char>(in_[2])) << 8) | static_cast<unsigned char>(in_[3]);
        off = 4;
      } else if (len == 127) {
        if (in_.size() < 10) return std::nullopt;
        len = 0;
        for (int i = 0; i < 8; ++i) len = (len << 8) | static_cast<unsigned char>(in_[2 + i]);
        off = 10;
      }
      if (in_.size() < off + len) return std::nullopt;
      std::string payload = in_.substr(off, len);
      in_.erase(0, off + len);
      const int op = b0 & 0x0f;
      const bool fin = (b0 & 0x80) != 0;
      if (op == 8) {
        closed_ = true;
        return std::nullopt;
      }
      // A long message may come in fragments (a text frame, then continuations).
      if (op == 1 || (op == 0 && in_text_)) {
        text_.append(payload);
        in_text_ = !fin;
        if (fin) return std::exchange(text_, std::string());
      }
    }
  }
  int fd_ = -1;
  std::string in_;
  std::string text_;  // a fragmented text message so far
  bool in_text_ = false;
  bool closed_ = false;
};

// A daemon on its own thread; stopped and joined when destroyed.
class RunningDaemon {
 public:
  explicit RunningDaemon(cncstream::daemon::DaemonConfig c) : d_(std::make_unique<cncstream::daemon::Daemon>(std::move(c))) {
    thread_ = std::thread([this] { d_->run(); });
    http.port = d_->port();
  }
  ~RunningDaemon() { shutdown(); }
  void shutdown() {
    if (!d_) return;
    d_->stop();
    thread_.join();
    d_.reset();
  }
  cncstream::daemon::Daemon& daemon() { return *d_; }
  unsigned short port() const { return http.port; }
  Http http;

 private:
  std::unique_ptr<cncstream::daemon::Daemon> d_;
  std::thread thread_;
};

inline cncstream::daemon::MachineConfig sim_machine(const std::string& name, const std::string& speed = "max") {
  cncstream::daemon::MachineConfig m;
  m.name = name;
  m.port = "sim";
  m.sim_speed = speed;
  m.reconnect_s = 0.2;
  return m;
}

inline cncstream::daemon::DaemonConfig test_config(const fs::path& dir) {
  cncstream::daemon::DaemonConfig c;
  c.listen_address = "127.0.0.1";
  c.listen_port = 0;
  c.data_dir = dir / "data";
  c.journal = dir / "journal.sqlite";
  c.web_root = dir / "web";
  fs::create_directories(c.web_root);
  std::ofstream(c.web_root / "index.html") << "<!doctype html><title>cncstream</title>";
  c.machines = {sim_machine("sim1"), sim_machine("sim2")};
  c.limits.worker_threads = 2;
  return c;
}

inline std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace dtest
