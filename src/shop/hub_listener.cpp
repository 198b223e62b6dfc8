#include "cncstream/shop/hub_listener.hpp"

#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <memory>

#include "cncstream/shop/pg.hpp"

namespace cncstream::shop {

HubListener::HubListener(std::string url, OnWake on_wake, double retry_s, double check_s, double reply_timeout_s)
    : url_(std::move(url)), on_wake_(std::move(on_wake)), retry_s_(retry_s), check_s_(check_s),
      reply_timeout_s_(reply_timeout_s) {
  stop_fd_ = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (stop_fd_ < 0) throw ShopError("shop: the hub listener cannot make an eventfd");
  thread_ = std::thread([this] { run(); });
}

HubListener::~HubListener() {
  {
    std::lock_guard lk(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  const std::uint64_t one = 1;
  [[maybe_unused]] const auto n = ::write(stop_fd_, &one, sizeof one);
  if (thread_.joinable()) thread_.join();
  ::close(stop_fd_);
}

bool HubListener::sleep_unless_stopped(double s) {
  std::unique_lock lk(mu_);
  return !cv_.wait_for(lk, std::chrono::duration<double>(s), [this] { return stop_; });
}

void HubListener::run() {
  bool said_down = false;
  while (true) {
    {
      std::lock_guard lk(mu_);
      if (stop_) return;
    }
    std::unique_ptr<PgConnection> db;
    try {
      db = std::make_unique<PgConnection>(url_, reply_timeout_s_);
      db->exec(std::string("LISTEN ") + kStateChannel);
    } catch (const std::exception& e) {
      if (!said_down) spdlog::warn("shop: the hub's wake-ups are not heard ({}); the shop view is read on request", e.what());
      said_down = true;
      if (!sleep_unless_stopped(retry_s_)) return;
      continue;
    }
    if (said_down) spdlog::info("shop: listening to the hub {} again", redact_url(url_));
    said_down = false;
    listening_ = true;
    ++connections_;
    on_wake_({{}, true});
    try {
      auto last_heard = std::chrono::steady_clock::now();
      while (true) {
        pollfd fds[2] = {{db->socket(), POLLIN, 0}, {stop_fd_, POLLIN, 0}};
        const int rc = ::poll(fds, 2, static_cast<int>(check_s_ * 1000));
        if (rc < 0 && errno != EINTR) throw ShopError("shop: the hub listener's poll failed");
        if (fds[1].revents) {
          listening_ = false;
          return;
        }
        if (rc == 0 || std::chrono::steady_clock::now() - last_heard > std::chrono::duration<double>(check_s_)) {
          // Silence for a while: ask, so a hub that vanished without closing is noticed.
          db->exec("SELECT 1");
          last_heard = std::chrono::steady_clock::now();
        }
        if (rc < 0) continue;
        auto got = db->take_notifications();  // throws when the hub went away
        last_heard = std::chrono::steady_clock::now();
        if (got.empty()) continue;
        HubWake w;
        for (auto& n : got)
          if (n.channel == kStateChannel && std::find(w.payloads.begin(), w.payloads.end(), n.payload) == w.payloads.end())
            w.payloads.push_back(std::move(n.payload));
        if (!w.payloads.empty()) on_wake_(std::move(w));
      }
    } catch (const std::exception& e) {
      listening_ = false;
      spdlog::warn("shop: the hub's wake-ups stopped ({}); listening again when it is back", e.what());
      said_down = true;
      db.reset();
      if (!sleep_unless_stopped(std::min(retry_s_, 0.2))) return;
    }
  }
}

}  // namespace cncstream::shop
