#pragma once
// The shop view pushed (docs/shop.md, "The shop view"; docs/api-v1.md, the
// `shop` frame): the hub's wake-ups (shop::HubListener, its own connection
// and thread) make the daemon read the machines and jobs they name through
// the view's reader (its own connection and thread, shop.view_changes) and
// send those rows to its WebSocket clients, which apply them to what they
// show; after the listener (re)connected, or a burst of more than a frame
// carries, the frame asks them to read the whole view instead. Bursts
// coalesce: at most one read in flight and one waiting, the waiting one
// carrying every wake-up's payloads, and reads start at most every
// `min_interval_s` (a busy shop wakes every daemon many times a second).
// Everything but the two threads runs
// on the event loop, which never waits on the hub. A read the hub does not
// answer is tried again a second later (its wake-ups kept); a hub that is
// down costs nothing here but the listener's retries.
#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "cncstream/shop/hub_listener.hpp"
#include "cncstream/shop/shop_view.hpp"

namespace cncstream::daemon {

class WsHub;

class ShopWatch {
 public:
  ShopWatch(boost::asio::io_context& io, shop::ShopViewReader& view, WsHub& hub, const std::string& url,
            double min_interval_s = kMinIntervalS);
  static constexpr double kMinIntervalS = 0.2;
  ~ShopWatch();  // before the view reader and the WebSocket hub go
  ShopWatch(const ShopWatch&) = delete;
  ShopWatch& operator=(const ShopWatch&) = delete;

  bool listening() const { return listener_ && listener_->listening(); }
  // Frames sent and reads made (the event loop's figures; for tests and benchmarks).
  std::uint64_t frames_sent() const { return frames_sent_; }
  std::uint64_t reads() const { return reads_; }

 private:
  void wake(shop::HubWake w);  // the event loop
  void request();  // a read now, or when the interval allows
  void arm(boost::asio::steady_timer::time_point at);
  void start_read();
  void read_done(shop::ViewAnswer a, std::vector<std::string> changed, bool resync);
  void send_whole(std::vector<std::string> changed, bool resync);

  boost::asio::io_context& io_;
  shop::ShopViewReader& view_;
  WsHub& hub_;
  std::shared_ptr<std::atomic<bool>> alive_ = std::make_shared<std::atomic<bool>>(true);
  bool in_flight_ = false;
  bool queued_ = false;
  std::vector<std::string> pending_;  // the waiting read's payloads
  bool pending_resync_ = false;
  std::chrono::steady_clock::duration min_interval_;
  std::chrono::steady_clock::time_point last_start_{};
  boost::asio::steady_timer timer_;  // the next read: paced, or a failed one again in a second
  bool timer_armed_ = false;
  bool failed_ = false;  // the last read: the hub did not answer
  std::atomic<std::uint64_t> frames_sent_{0}, reads_{0};
  std::unique_ptr<shop::HubListener> listener_;  // last: its thread stops first
};

}  // namespace cncstream::daemon
