#pragma once
// A scripted GRBL 1.1 on the master side of a pseudo-terminal, for transport
// and runner tests: banner on reset(), $I, ok per line (or error:N for chosen
// lines), '?' status, '!' hold -> Hold:0, 0x18 reset -> banner. It checks the
// RX buffer never holds more than 127 unprocessed bytes.
#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

class FakeGrbl {
 public:
  FakeGrbl() {
    master_ = ::posix_openpt(O_RDWR | O_NOCTTY);
    if (master_ < 0 || ::grantpt(master_) != 0 || ::unlockpt(master_) != 0) std::abort();
    slave_ = ::ptsname(master_);
  }
  ~FakeGrbl() {
    stop();
    if (master_ >= 0) ::close(master_);
  }
  const std::string& slave_path() const { return slave_; }

  std::map<int, int> errors;        // file line number (1-based count of G-code lines) -> error code
  int disconnect_after = -1;        // close the pty after answering this many G-code lines
  int lines_per_step = 2;           // processing speed: lines executed per 1 ms step

  void start() { thread_ = std::thread([this] { loop(); }); }
  void stop() {
    running_ = false;
    if (thread_.joinable()) thread_.join();
  }
  void reset() { reset_requested_ = true; }  // what a DTR pulse does

  std::size_t max_rx() const { return max_rx_; }
  bool overflowed() const { return overflow_; }
  int answered() const { return answered_; }
  std::vector<std::string> received() {
    std::lock_guard<std::mutex> l(mu_);
    return lines_;
  }
  int resets() const { return resets_; }
  std::string realtime_seen() {
    std::lock_guard<std::mutex> l(mu_);
    return realtime_seen_;
  }

 private:
  void send(const std::string& s) {
    if (master_ >= 0 && ::write(master_, s.data(), s.size()) < 0) {}
  }
  void banner() {
    rx_.clear();
    hold_ = false;
    send("\r\nGrbl 1.1h ['$' for help]\r\n");
    ++resets_;
  }
  void loop() {
    using namespace std::chrono;
    while (running_) {
      if (reset_requested_.exchange(false)) {
        std::this_thread::sleep_for(milliseconds(20));
        banner();
      }
      pollfd p{master_, POLLIN, 0};
      if (::poll(&p, 1, 1) > 0 && (p.revents & POLLIN)) {
        char buf[512];
        const ssize_t n = ::read(master_, buf, sizeof buf);
        for (ssize_t i = 0; i < n; ++i) take(static_cast<unsigned char>(buf[i]));
      }
      if (!hold_) process(lines_per_step);
      if (disconnect_after >= 0 && answered_ >= disconnect_after) {
        std::this_thread::sleep_for(milliseconds(50));  // let the last answers reach the host
        ::close(master_);
        master_ = -1;
        return;
      }
    }
  }
  void take(unsigned char c) {
    if (c == '?') {
      send(std::string("<") + (hold_ ? "Hold:0" : (rx_.empty() ? "Idle" : "Run")) +
           "|MPos:1.000,2.000,3.000|Bf:15," + std::to_string(127 - rx_.size()) + "|FS:0,0|WCO:0,0,0>\r\n");
      return;
    }
    if (c == '!') { hold_ = true; return; }
    if (c == '~') { hold_ = false; return; }
    if (c == 0x18) { banner(); return; }
    if (c >= 0x80) {
      std::lock_guard<std::mutex> l(mu_);
      realtime_seen_.push_back(static_cast<char>(c));
      return;
    }
    rx_.push_back(static_cast<char>(c));
    if (rx_.size() > 127) overflow_ = true;
    if (rx_.size() > max_rx_) max_rx_ = rx_.size();
  }
  void process(int n) {
    for (int k = 0; k < n; ++k) {
      const auto nl = rx_.find('\n');
      if (nl == std::string::npos) return;
      const std::string line = rx_.substr(0, nl);
      rx_.erase(0, nl + 1);
      {
        std::lock_guard<std::mutex> l(mu_);
        lines_.push_back(line);
      }
      if (line == "$I") {
        send("[VER:1.1h.20190830:]\r\n[OPT:V,15,128]\r\nok\r\n");
        continue;
      }
      ++gcode_lines_;
      auto it = errors.find(gcode_lines_);
      if (it != errors.end()) send("error:" + std::to_string(it->second) + "\r\n");
      else send("ok\r\n");
      ++answered_;
    }
  }

  int master_ = -1;
  std::string slave_;
  std::thread thread_;
  std::atomic<bool> running_{true};
  std::atomic<bool> reset_requested_{false};
  std::string rx_;
  bool hold_ = false;
  std::atomic<std::size_t> max_rx_{0};
  std::atomic<bool> overflow_{false};
  std::atomic<int> answered_{0};
  std::atomic<int> resets_{0};
  int gcode_lines_ = 0;
  std::mutex mu_;
  std::vector<std::string> lines_;
  std::string realtime_seen_;
};
