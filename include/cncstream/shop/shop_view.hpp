#pragma once
// The shop view's reads (docs/shop.md, "The shop view"): every machine of
// every PC with its state, the queue and history with filters, a job's
// events, through the hub's read-only functions (shop.view_*), so a PC's
// login serves them. The reader has a connection and a thread of its own:
// a daemon's event loop never waits on PostgreSQL, and a hub that is down
// answers at once with why (its URL without the password) while the rest of
// the daemon runs on.
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "cncstream/shop/pg.hpp"

namespace cncstream::shop {

// The statuses a shop job goes through (shop.jobs.status).
const std::vector<std::string>& job_statuses();

struct JobFilter {
  std::vector<std::string> statuses;  // empty: any
  std::string machine;                // "": any; else the machine it went to or asks for
  int limit = 100;                    // 1..500
  std::int64_t before = 0;            // 0: the newest; else ids below it (the next page)
};

// The reads themselves, on a connection of the caller's (throws ShopError).
nlohmann::json view_machines(PgConnection& db);
nlohmann::json view_jobs(PgConnection& db, const JobFilter& f);
// The machines and jobs a wake-up named ("machine:NAME", "job:ID"; others
// ignored), as view_machines and view_jobs show them, with the machine each
// job is on: {"now", "machines": [...], "jobs": [...]} (migration 5).
nlohmann::json view_changes(PgConnection& db, const std::vector<std::string>& payloads);
// nullopt: no such job.
std::optional<nlohmann::json> view_job_events(PgConnection& db, std::int64_t job, int limit);

struct ViewAnswer {
  // refused: the hub answered and said no (a function's RAISE EXCEPTION, a
  // right the login lacks, a value it rejects); `sqlstate` says which.
  enum class Kind { ok, not_found, hub_unavailable, refused };
  Kind kind = Kind::ok;
  nlohmann::json body;  // ok
  std::string message;  // otherwise (refused: the server's own words)
  std::string sqlstate;  // refused
};

// Also carries the web page's operator acts (submit, cancel, requeue: the
// hub's functions, each one statement), which must not wait on the event
// loop either.
class ShopViewReader {
 public:
  // A read: returns the answer's body, nullopt for "not found"; throws ShopError.
  using Read = std::function<std::optional<nlohmann::json>(PgConnection&)>;
  using Done = std::function<void(ViewAnswer)>;

  // `retry_s`: after a failed connection, reads fail at once with its reason
  // for this long instead of each waiting for the connect time-out.
  // `reply_timeout_s`: a read the hub does not answer this long fails (503)
  // and drops the connection (a hub that vanished without closing it).
  explicit ShopViewReader(std::string url, double retry_s = 1.0, std::size_t max_pending = 32,
                          double reply_timeout_s = 3.0);
  ~ShopViewReader();  // answers what still waits "stopping", joins the thread
  ShopViewReader(const ShopViewReader&) = delete;
  ShopViewReader& operator=(const ShopViewReader&) = delete;

  // Queues a read; `done` is called once, on the reader's thread (or here,
  // at once, when too many wait).
  void submit(Read read, Done done);

 private:
  void worker();
  ViewAnswer answer(const Read& read);

  std::string url_;
  double retry_s_;
  std::size_t max_pending_;
  double reply_timeout_s_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<std::pair<Read, Done>> queue_;
  bool stop_ = false;
  // The worker's own.
  std::unique_ptr<PgConnection> db_;
  double down_until_ = 0;
  std::string down_reason_;
  std::thread thread_;
};

}  // namespace cncstream::shop
