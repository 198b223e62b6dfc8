#pragma once
// A throw-away Mosquitto broker on 127.0.0.1 and a free port (no
// persistence: a restart forgets retained messages), and a subscriber that
// keeps what it received. Tests skip when the broker is not installed.
#include <mosquitto.h>

#include <fstream>
#include <map>
#include <mutex>
#include <vector>

#include "shop_test_util.hpp"

namespace shoptest {

class TempMosquitto {
 public:
  static std::string program() { return find_program("mosquitto", {"/usr/sbin", "/usr/local/sbin"}); }
  static bool available() { return !program().empty(); }
  TempMosquitto() : dir_(temp_dir("mqtt")), port_(free_port()) {
    std::ofstream(dir_ / "mosquitto.conf") << "listener " << port_ << " 127.0.0.1\nallow_anonymous true\npersistence false\n";
    start();
  }
  ~TempMosquitto() {
    stop();
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  unsigned short port() const { return port_; }
  void start() {
    if (pid_ > 0) return;
    pid_ = spawn({program(), "-c", (dir_ / "mosquitto.conf").string()}, RunAs{}, dir_ / "broker.log");
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (std::chrono::steady_clock::now() < end) {
      const int fd = loopback_connect();
      if (fd >= 0) {
        ::close(fd);
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    throw std::runtime_error("mosquitto did not start: see " + (dir_ / "broker.log").string());
  }
  void stop() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGTERM);
    int st = 0;
    ::waitpid(pid_, &st, 0);
    pid_ = -1;
  }

 private:
  int loopback_connect() const {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(port_);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0) return fd;
    ::close(fd);
    return -1;
  }
  fs::path dir_;
  unsigned short port_;
  pid_t pid_ = -1;
};

// Subscribes to a pattern; keeps each topic's last payload and every message in order.
class Subscriber {
 public:
  Subscriber(unsigned short port, const std::string& pattern) : pattern_(pattern) {
    mosquitto_lib_init();
    m_ = mosquitto_new(nullptr, true, this);
    mosquitto_connect_callback_set(m_, [](mosquitto* m, void* self, int) {
      mosquitto_subscribe(m, nullptr, static_cast<Subscriber*>(self)->pattern_.c_str(), 1);
    });
    mosquitto_message_callback_set(m_, [](mosquitto*, void* self, const mosquitto_message* msg) {
      auto* me = static_cast<Subscriber*>(self);
      std::lock_guard lock(me->mu_);
      std::string payload(static_cast<const char*>(msg->payload), static_cast<std::size_t>(msg->payloadlen));
      me->last_[msg->topic] = payload;
      me->all_.emplace_back(msg->topic, payload);
    });
    mosquitto_connect(m_, "127.0.0.1", port, 5);
    mosquitto_loop_start(m_);
  }
  ~Subscriber() {
    mosquitto_disconnect(m_);
    mosquitto_loop_stop(m_, true);
    mosquitto_destroy(m_);
  }
  std::optional<std::string> last(const std::string& topic) {
    std::lock_guard lock(mu_);
    const auto it = last_.find(topic);
    if (it == last_.end()) return std::nullopt;
    return it->second;
  }
  std::vector<std::string> payloads(const std::string& topic) {
    std::lock_guard lock(mu_);
    std::vector<std::string> out;
    for (const auto& [t, p] : all_)
      if (t == topic) out.push_back(p);
    return out;
  }

 private:
  std::string pattern_;
  mosquitto* m_ = nullptr;
  std::mutex mu_;
  std::map<std::string, std::string> last_;
  std::vector<std::pair<std::string, std::string>> all_;
};

#define SHOP_REQUIRE_MOSQUITTO()                                                                        \
  do {                                                                                                  \
    if (!shoptest::TempMosquitto::available())                                                          \
      GTEST_SKIP() << "the mosquitto broker is not installed (scripts/setup.sh installs mosquitto)";    \
  } while (0)

}  // namespace shoptest
