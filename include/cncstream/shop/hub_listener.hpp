#pragma once
// The hub's wake-ups (docs/shop.md, "The shop view"): a PostgreSQL
// connection of its own that LISTENs on `cncstream_state` (migration 3's
// triggers NOTIFY it when a machine's state or a job changes), on a thread
// of its own, so the daemon's event loop never waits on the hub. A
// notification is a wake-up only: the listener passes on the payloads
// ("machine:NAME", "job:ID") and the caller re-reads what it shows. After a
// hub outage it connects again every `retry_s` and LISTENs again; each
// (re)connection is reported as a wake-up too (`resync`), since whatever
// changed while it was away sent nothing it could hear.
#include <atomic>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace cncstream::shop {

// The channel migration 3's triggers notify.
inline constexpr const char* kStateChannel = "cncstream_state";

struct HubWake {
  std::vector<std::string> payloads;  // in arrival order, repeats removed
  bool resync = false;                // the listener has just (re)connected
};

class HubListener {
 public:
  // Called on the listener's thread; must not block for long.
  using OnWake = std::function<void(HubWake)>;
  // A connection quiet for `check_s` is asked (SELECT 1), and one that does
  // not answer within `reply_timeout_s` is dropped (a hub that vanished
  // without closing it): noticed within about check_s + reply_timeout_s.
  HubListener(std::string url, OnWake on_wake, double retry_s = 1.0, double check_s = 1.0,
              double reply_timeout_s = 3.0);
  ~HubListener();  // stops and joins the thread
  HubListener(const HubListener&) = delete;
  HubListener& operator=(const HubListener&) = delete;

  // Whether it LISTENs now.
  bool listening() const { return listening_; }
  // How many times it has connected and LISTENed (1 after the first).
  int connections() const { return connections_; }

 private:
  void run();
  bool sleep_unless_stopped(double s);

  std::string url_;
  OnWake on_wake_;
  double retry_s_, check_s_, reply_timeout_s_;
  int stop_fd_ = -1;  // an eventfd: written to stop the poll
  std::mutex mu_;
  std::condition_variable cv_;
  bool stop_ = false;
  std::atomic<bool> listening_{false};
  std::atomic<int> connections_{0};
  std::thread thread_;
};

}  // namespace cncstream::shop
