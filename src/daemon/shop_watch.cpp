#include "cncstream/daemon/shop_watch.hpp"

#include <boost/asio/post.hpp>

#include <algorithm>

#include "cncstream/daemon/ws_hub.hpp"
#include "cncstream/daemon/http_types.hpp"

namespace cncstream::daemon {

namespace detail_shop_watch {
// A frame names at most this many changes (a burst over many machines says
// "more": the view itself is whole either way).
constexpr std::size_t kMaxChanged = 64;
}  // namespace detail_shop_watch

ShopWatch::ShopWatch(boost::asio::io_context& io, shop::ShopViewReader& view, WsHub& hub, const std::string& url)
    : io_(io), view_(view), hub_(hub), retry_(io) {
  listener_ = std::make_unique<shop::HubListener>(url, [this, alive = alive_](shop::HubWake w) {
    boost::asio::post(io_, [this, alive, w = std::move(w)]() mutable {
      if (*alive) wake(std::move(w));
    });
  });
}

ShopWatch::~ShopWatch() {
  *alive_ = false;
  listener_.reset();
  retry_.cancel();
}

void ShopWatch::wake(shop::HubWake w) {
  for (auto& p : w.payloads)
    if (std::find(pending_.begin(), pending_.end(), p) == pending_.end()) pending_.push_back(std::move(p));
  pending_resync_ = pending_resync_ || w.resync;
  if (in_flight_) {
    queued_ = true;  // one read waits, with every payload since
    return;
  }
  start_read();
}

void ShopWatch::start_read() {
  in_flight_ = true;
  queued_ = false;
  auto changed = std::move(pending_);
  pending_.clear();
  const bool resync = pending_resync_;
  pending_resync_ = false;
  ++reads_;
  view_.submit([](shop::PgConnection& db) -> std::optional<nlohmann::json> { return shop::view_machines(db); },
               [this, alive = alive_, changed = std::move(changed), resync](shop::ViewAnswer a) mutable {
                 boost::asio::post(io_, [this, alive, a = std::move(a), changed = std::move(changed), resync]() mutable {
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
    retry_.expires_after(std::chrono::seconds(1));
    retry_.async_wait([this, alive = alive_](const boost::system::error_code& ec) {
      if (!ec && *alive && !in_flight_ && listening()) start_read();
    });
    return;
  }
  {
    nlohmann::json f = {{"type", "shop"}, {"now", a.body.value("now", nlohmann::json())},
                        {"machines", a.body.value("machines", nlohmann::json::array())}, {"resync", resync}};
    const bool more = changed.size() > detail_shop_watch::kMaxChanged;
    if (more) changed.resize(detail_shop_watch::kMaxChanged);
    f["changed"] = std::move(changed);
    f["more"] = more;
    hub_.broadcast(WsHub::frame(dump_json(f)));
    ++frames_sent_;
  }
  if (queued_) start_read();
}

}  // namespace cncstream::daemon
