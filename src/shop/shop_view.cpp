#include "cncstream/shop/shop_view.hpp"

#include <chrono>

#include "cncstream/shop/hub.hpp"

namespace cncstream::shop {

namespace detail_shop_view {

double steady_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

nlohmann::json parse(const PgResult& r, const char* what) {
  try {
    return nlohmann::json::parse(r.text(0, 0));
  } catch (const nlohmann::json::exception& e) {
    throw ShopError(std::string("shop hub: ") + what + " returned JSON that does not parse: " + e.what());
  }
}

}  // namespace detail_shop_view

const std::vector<std::string>& job_statuses() {
  static const std::vector<std::string> all = {"pending", "assigned",    "awaiting_operator", "running",
                                               "completed", "failed",    "interrupted",       "cancelled"};
  return all;
}

nlohmann::json view_machines(PgConnection& db) {
  return detail_shop_view::parse(db.exec("SELECT shop.view_machines()"), "view_machines");
}

nlohmann::json view_jobs(PgConnection& db, const JobFilter& f) {
  PgParams p = {f.statuses.empty() ? std::nullopt : std::optional<std::string>(pg_text_array(f.statuses)),
                f.machine.empty() ? std::nullopt : std::optional<std::string>(f.machine), std::to_string(f.limit),
                f.before > 0 ? std::optional<std::string>(std::to_string(f.before)) : std::nullopt};
  return detail_shop_view::parse(db.exec("SELECT shop.view_jobs($1::text[], $2, $3::integer, $4::bigint)", p),
                                 "view_jobs");
}

nlohmann::json view_changes(PgConnection& db, const std::vector<std::string>& payloads) {
  std::vector<std::string> machines, jobs;
  for (const auto& p : payloads) {
    if (p.rfind("machine:", 0) == 0) {
      machines.push_back(p.substr(8));
    } else if (p.rfind("job:", 0) == 0) {
      const auto id = p.substr(4);
      if (!id.empty() && id.size() < 19 && id.find_first_not_of("0123456789") == std::string::npos) jobs.push_back(id);
    }
  }
  return detail_shop_view::parse(db.exec("SELECT shop.view_changes($1::text[], $2::bigint[])",
                                         {pg_text_array(machines), pg_text_array(jobs)}),
                                 "view_changes");
}

std::optional<nlohmann::json> view_job_events(PgConnection& db, std::int64_t job, int limit) {
  const auto r = db.exec("SELECT shop.view_job_events($1::bigint, $2::integer)", {std::to_string(job), std::to_string(limit)});
  if (r.rows() == 0 || r.is_null(0, 0)) return std::nullopt;
  return detail_shop_view::parse(r, "view_job_events");
}

ShopViewReader::ShopViewReader(std::string url, double retry_s, std::size_t max_pending, double reply_timeout_s)
    : url_(std::move(url)), retry_s_(retry_s), max_pending_(max_pending), reply_timeout_s_(reply_timeout_s) {
  thread_ = std::thread([this] { worker(); });
}

ShopViewReader::~ShopViewReader() {
  {
    std::lock_guard lk(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  for (auto& [read, done] : queue_) done({ViewAnswer::Kind::hub_unavailable, {}, "the daemon is stopping", {}});
}

void ShopViewReader::submit(Read read, Done done) {
  {
    std::lock_guard lk(mu_);
    if (queue_.size() < max_pending_) {
      queue_.emplace_back(std::move(read), std::move(done));
      cv_.notify_one();
      return;
    }
  }
  done({ViewAnswer::Kind::hub_unavailable, {},
        "shop hub " + redact_url(url_) + ": " + std::to_string(max_pending_) + " reads already wait for it; try again", {}});
}

void ShopViewReader::worker() {
  for (;;) {
    std::pair<Read, Done> item;
    {
      std::unique_lock lk(mu_);
      cv_.wait(lk, [&] { return stop_ || !queue_.empty(); });
      if (stop_) return;
      item = std::move(queue_.front());
      queue_.pop_front();
    }
    item.second(answer(item.first));
  }
}

ViewAnswer ShopViewReader::answer(const Read& read) {
  using Kind = ViewAnswer::Kind;
  for (int attempt = 0; attempt < 2; ++attempt) {
    if (!db_ || !db_->ok()) {
      db_.reset();
      if (detail_shop_view::steady_s() < down_until_) return {Kind::hub_unavailable, {}, down_reason_, {}};
      try {
        db_ = std::make_unique<PgConnection>(url_, reply_timeout_s_);
        // A hub that hangs must not hold the view's thread for long.
        db_->exec("SET statement_timeout = 5000");
      } catch (const ShopError& e) {
        db_.reset();
        down_until_ = detail_shop_view::steady_s() + retry_s_;
        down_reason_ = e.what();
        return {Kind::hub_unavailable, {}, down_reason_, {}};
      }
    }
    try {
      auto body = read(*db_);
      if (!body) return {Kind::not_found, {}, {}, {}};
      return {Kind::ok, std::move(*body), {}, {}};
    } catch (const ShopError& e) {
      if (db_->last_sqlstate() == "42883")  // undefined_function: a hub migrated by an older program
        return {Kind::hub_unavailable, {},
                "shop hub " + redact_url(url_) +
                    ": its schema has no shop view (shop.view_*): run `cncstream shop init URL` as its administrator", {}};
      // The hub said no (the connection is fine): its words, for the caller to map.
      const std::string& st = db_->last_sqlstate();
      if (db_->ok() && (st == "P0001" || st == "42501" || st.rfind("22", 0) == 0 || st.rfind("23", 0) == 0))
        return {Kind::refused, {}, db_->last_error(), st};
      // A hub that does not answer: the next reads say so at once for a while.
      if (db_->timed_out()) {
        down_until_ = detail_shop_view::steady_s() + retry_s_;
        down_reason_ = e.what();
        return {Kind::hub_unavailable, {}, down_reason_, {}};
      }
      // A connection the server dropped (a restart): once more on a fresh one.
      if (!db_->ok() && attempt == 0) continue;
      return {Kind::hub_unavailable, {}, e.what(), {}};
    } catch (const std::exception& e) {  // never lets the reader's thread end
      return {Kind::hub_unavailable, {}, "shop hub " + redact_url(url_) + ": " + e.what(), {}};
    }
  }
  return {Kind::hub_unavailable, {}, "shop hub " + redact_url(url_) + ": the connection was lost", {}};
}

}  // namespace cncstream::shop
