#include "cncstream/daemon/shop_watch.hpp"

#include <boost/asio/post.hpp>

#include <algorithm>

#include "cncstream/daemon/ws_hub.hpp"
#include "cncstream/daemon/http_types.hpp"

namespace cncstream::daemon {

namespace detail_shop_watch {
// A frame carries at most this many changes; a burst over more says "more"
// and the pages read the whole view.
constexpr std::size_t kMaxChanged = 64;
}  // namespace detail_shop_watch

ShopWatch::ShopWatch(boost::asio::io_context& io, shop::ShopViewReader& view, WsHub& hub, const std::string& url,
                     double min_interval_s)
    : io_(io),
      view_(view),
      hub_(hub),
      min_interval_(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
          std::chrono::duration<double>(min_interval_s))),
      timer_(io) {
  // The callbacks of the other threads hold the io_context (the daemon's),
  // never this, until the alive flag says this still exists.
  listener_ = std::make_unique<shop::HubListener>(url, [this, &io, alive = alive_](shop::HubWake w) {
    boost::asio::post(io, [this, alive, w = std::move(w)]() mutable {
      if (*alive) wake(std::move(w));
    });
  });
}

ShopWatch::~ShopWatch() {
  *alive_ = false;
  listener_.reset();
  timer_.cancel();
}

void ShopWatch::wake(shop::HubWake w) {
  for (auto& p : w.payloads)
    if (std::find(pending_.begin(), pending_.end(), p) == pending_.end()) pending_.push_back(std::move(p));
  pending_resync_ = pending_resync_ || w.resync;
  request();
}

void ShopWatch::request() {
  if (in_flight_ || timer_armed_) {
    queued_ = true;  // one read waits, with every payload since
    return;
  }
  const auto due = last_start_ + min_interval_;
  if (std::chrono::steady_clock::now() >= due) start_read();
  else arm(due);
}

void ShopWatch::arm(boost::asio::steady_timer::time_point at) {
  timer_armed_ = true;
  timer_.expires_at(at);
  timer_.async_wait([this, alive = alive_](const boost::system::error_code& ec) {
    if (ec || !*alive) return;
    timer_armed_ = false;
    // After a failed read, only while the hub is heard (else its return's resync reads).
    if (!in_flight_ && (!failed_ || listening())) start_read();
  });
}

void ShopWatch::start_read() {
  queued_ = false;
  last_start_ = std::chrono::steady_clock::now();
  auto changed = std::move(pending_);
  pending_.clear();
  const bool resync = pending_resync_;
  pending_resync_ = false;
  if (resync || changed.size() > detail_shop_watch::kMaxChanged) {
    // The page reads the whole view itself: nothing to read here.
    send_whole(std::move(changed), resync);
    if (queued_) request();
    return;
  }
  in_flight_ = true;
  ++reads_;
  // The read's own copy: the answer's callback takes `changed` itself (the
  // two arguments are built in no set order).
  shop::ShopViewReader::Read read = [payloads = changed](shop::PgConnection& db) -> std::optional<nlohmann::json> {
    return shop::view_changes(db, payloads);
  };
  view_.submit(std::move(read),
               [this, &io = io_, alive = alive_, changed = std::move(changed), resync](shop::ViewAnswer a) mutable {
                 boost::asio::post(io, [this, alive, a = std::move(a), changed = std::move(changed), resync]() mutable {
                   if (*alive) read_done(std::move(a), std::move(changed), resync);
                 });
               });
}

void ShopWatch::read_done(shop::ViewAnswer a, std::vector<std::string> changed, bool resync) {
  in_flight_ = false;
  if (a.kind != shop::ViewAnswer::Kind::ok) {
    // Fail soft: nothing is sent (the page's slow poll says why); the
    // wake-ups wait for a read a second later, or for the next wake-up.
    for (auto& c : changed)
      if (std::find(pending_.begin(), pending_.end(), c) == pending_.end()) pending_.push_back(std::move(c));
    pending_resync_ = pending_resync_ || resync;
    failed_ = true;
    arm(std::chrono::steady_clock::now() + std::chrono::seconds(1));
    return;
  }
  failed_ = false;
  nlohmann::json f = {{"type", "shop"},
                      {"now", a.body.value("now", nlohmann::json())},
                      {"machines", a.body.value("machines", nlohmann::json::array())},
                      {"jobs", a.body.value("jobs", nlohmann::json::array())},
                      {"resync", resync},
                      {"more", false},
                      {"changed", std::move(changed)}};
  hub_.broadcast(WsHub::frame(dump_json(f)));
  ++frames_sent_;
  if (queued_) request();
}

// A frame that asks the pages to read the whole view: after the listener
// (re)connected (whatever changed meanwhile sent nothing), or after more
// changes than a frame names.
void ShopWatch::send_whole(std::vector<std::string> changed, bool resync) {
  const bool more = changed.size() > detail_shop_watch::kMaxChanged;
  if (more) changed.resize(detail_shop_watch::kMaxChanged);
  nlohmann::json f = {{"type", "shop"}, {"now", nullptr}, {"machines", nlohmann::json::array()},
                      {"jobs", nlohmann::json::array()}, {"resync", resync}, {"more", more},
                      {"changed", std::move(changed)}};
  hub_.broadcast(WsHub::frame(dump_json(f)));
  ++frames_sent_;
}

}  // namespace cncstream::daemon
