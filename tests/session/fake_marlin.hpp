#pragma once
// A scripted Marlin on a pseudo-terminal: banner on reset(), M115, M110, and
// numbered lines with checksums. Line number `corrupt_once` is "received
// corrupted" the first time, so the host must resend it.
#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <string>
#include <thread>

class FakeMarlin {
 public:
  FakeMarlin() {
    master_ = ::posix_openpt(O_RDWR | O_NOCTTY);
    if (master_ < 0 || ::grantpt(master_) != 0 || ::unlockpt(master_) != 0) std::abort();
    slave_ = ::ptsname(master_);
  }
  ~FakeMarlin() {
    running_ = false;
    if (thread_.joinable()) thread_.join();
    ::close(master_);
  }
  const std::string& slave_path() const { return slave_; }
  long corrupt_once = -1;
  void start() { thread_ = std::thread([this] { loop(); }); }
  void reset() { reset_requested_ = true; }
  int accepted() const { return accepted_; }
  int bad_checksums() const { return bad_; }

 private:
  void send(const std::string& s) {
    if (::write(master_, s.data(), s.size()) < 0) {}
  }
  void loop() {
    std::string rx;
    while (running_) {
      if (reset_requested_.exchange(false)) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        send("start\r\necho:Marlin 2.1.2.1\r\n");
      }
      pollfd p{master_, POLLIN, 0};
      if (::poll(&p, 1, 1) <= 0 || !(p.revents & POLLIN)) continue;
      char buf[512];
      const ssize_t n = ::read(master_, buf, sizeof buf);
      if (n > 0) rx.append(buf, static_cast<std::size_t>(n));
      for (auto nl = rx.find('\n'); nl != std::string::npos; nl = rx.find('\n')) {
        const std::string line = rx.substr(0, nl);
        rx.erase(0, nl + 1);
        handle(line);
      }
    }
  }
  void handle(const std::string& line) {
    if (line == "M115") {
      send("FIRMWARE_NAME:Marlin 2.1.2.1 (Jun  1 2023) MACHINE_TYPE:CNC\r\nCap:EEPROM:1\r\nok\r\n");
      return;
    }
    if (line == "M110 N0") {
      last_ = 0;
      send("ok\r\n");
      return;
    }
    const auto star = line.rfind('*');
    if (line.empty() || line[0] != 'N' || star == std::string::npos) {
      send("ok\r\n");
      return;
    }
    int cs = 0;
    for (std::size_t i = 0; i < star; ++i) cs ^= static_cast<unsigned char>(line[i]);
    const long n = std::strtol(line.c_str() + 1, nullptr, 10);
    bool ok = std::to_string(cs & 0xFF) == line.substr(star + 1);
    if (n == corrupt_once) {
      corrupt_once = -1;
      ok = false;
    }
    if (!ok) {
      ++bad_;
      send("Error:checksum mismatch, Last Line: " + std::to_string(last_) + "\r\nResend: " + std::to_string(last_ + 1) +
           "\r\nok\r\n");
      return;
    }
    if (n != last_ + 1) {
      send("Error:Line Number is not Last Line Number+1, Last Line: " + std::to_string(last_) + "\r\nResend: " +
           std::to_string(last_ + 1) + "\r\nok\r\n");
      return;
    }
    last_ = n;
    ++accepted_;
    if (n % 10 == 0) send("echo:busy: processing\r\n");
    send("ok N" + std::to_string(n) + " P15 B3\r\n");
  }

  int master_ = -1;
  std::string slave_;
  std::thread thread_;
  std::atomic<bool> running_{true};
  std::atomic<bool> reset_requested_{false};
  long last_ = 0;
  std::atomic<int> accepted_{0};
  std::atomic<int> bad_{0};
};
