#include "cncstream/shop/outbox.hpp"

#include <sqlite3.h>

#include "cncstream/transport/journal.hpp"

namespace cncstream::shop {

namespace detail_outbox {

// One prepared statement; errors name the journal.
class Query {
 public:
  Query(sqlite3* db, const std::filesystem::path& path, const char* sql) : db_(db), path_(path) {
    if (sqlite3_prepare_v2(db, sql, -1, &s_, nullptr) != SQLITE_OK) fail();
  }
  ~Query() { sqlite3_finalize(s_); }
  Query(const Query&) = delete;
  Query& operator=(const Query&) = delete;
  Query& text(int i, const std::string& v) {
    sqlite3_bind_text(s_, i, v.c_str(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
    return *this;
  }
  Query& num(int i, std::int64_t v) {
    sqlite3_bind_int64(s_, i, v);
    return *this;
  }
  bool step() {
    const int rc = sqlite3_step(s_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    fail();
  }
  std::string col_text(int c) const {
    const auto* p = sqlite3_column_text(s_, c);
    return p ? reinterpret_cast<const char*>(p) : "";
  }
  std::int64_t col_num(int c) const { return sqlite3_column_int64(s_, c); }

 private:
  [[noreturn]] void fail() { throw ShopError(path_.string() + ": outbox: " + sqlite3_errmsg(db_)); }
  sqlite3* db_;
  const std::filesystem::path& path_;
  sqlite3_stmt* s_ = nullptr;
};

}  // namespace detail_outbox

using detail_outbox::Query;

Outbox::Outbox(const std::filesystem::path& journal) : path_(journal) {
  if (sqlite3_open_v2(journal.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX,
                      nullptr) != SQLITE_OK) {
    const std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw ShopError(journal.string() + ": cannot open the journal for the outbox: " + msg);
  }
  sqlite3_busy_timeout(db_, 5000);
  try {
    exec("PRAGMA journal_mode=WAL");
    exec("PRAGMA synchronous=FULL");
    exec("CREATE TABLE IF NOT EXISTS shop_outbox ("
         " id INTEGER PRIMARY KEY AUTOINCREMENT, machine TEXT NOT NULL, seq INTEGER NOT NULL, at TEXT NOT NULL,"
         " kind TEXT NOT NULL, shop_job INTEGER NOT NULL DEFAULT 0, body TEXT NOT NULL, sent INTEGER NOT NULL DEFAULT 0,"
         " UNIQUE (machine, seq))");
    exec("CREATE INDEX IF NOT EXISTS shop_outbox_unsent ON shop_outbox (machine, sent, seq)");
    exec("CREATE TABLE IF NOT EXISTS shop_cursors (consumer TEXT NOT NULL, machine TEXT NOT NULL,"
         " seq INTEGER NOT NULL, PRIMARY KEY (consumer, machine))");
    exec("CREATE TABLE IF NOT EXISTS shop_jobs (local_id INTEGER PRIMARY KEY, shop_id INTEGER NOT NULL,"
         " machine TEXT NOT NULL)");
  } catch (...) {
    sqlite3_close(db_);
    db_ = nullptr;
    throw;
  }
}

Outbox::~Outbox() { sqlite3_close(db_); }

void Outbox::exec(const char* sql) const {
  char* err = nullptr;
  if (sqlite3_exec(db_, sql, nullptr, nullptr, &err) != SQLITE_OK) {
    const std::string msg = err ? err : "unknown error";
    sqlite3_free(err);
    throw ShopError(path_.string() + ": outbox: " + msg);
  }
}

std::int64_t Outbox::append(const std::string& machine, const std::string& kind, std::int64_t shop_job,
                            const std::string& body_json) {
  std::lock_guard lock(mu_);
  // One statement: the next number and the row commit together.
  Query q(db_, path_,
          "INSERT INTO shop_outbox (machine, seq, at, kind, shop_job, body) VALUES (?1,"
          " (SELECT coalesce(max(seq), 0) + 1 FROM shop_outbox WHERE machine = ?1), ?2, ?3, ?4, ?5) RETURNING seq");
  q.text(1, machine).text(2, transport::Journal::now_iso8601()).text(3, kind).num(4, shop_job).text(5, body_json);
  q.step();
  const auto seq = q.col_num(0);
  while (q.step()) {
  }
  return seq;
}

std::vector<OutboxEvent> Outbox::unsent(const std::string& machine, int limit) const {
  std::lock_guard lock(mu_);
  Query q(db_, path_,
          "SELECT seq, at, kind, shop_job, body FROM shop_outbox WHERE machine = ?1 AND sent = 0 ORDER BY seq LIMIT ?2");
  q.text(1, machine).num(2, limit);
  std::vector<OutboxEvent> out;
  while (q.step()) out.push_back({q.col_num(0), q.col_text(1), q.col_text(2), q.col_num(3), q.col_text(4)});
  return out;
}

std::vector<std::string> Outbox::machines_with_unsent() const {
  std::lock_guard lock(mu_);
  Query q(db_, path_, "SELECT DISTINCT machine FROM shop_outbox WHERE sent = 0");
  std::vector<std::string> out;
  while (q.step()) out.push_back(q.col_text(0));
  return out;
}

void Outbox::mark_sent(const std::string& machine, std::int64_t up_to_seq) {
  std::lock_guard lock(mu_);
  Query q(db_, path_, "UPDATE shop_outbox SET sent = 1 WHERE machine = ?1 AND seq <= ?2 AND sent = 0");
  q.text(1, machine).num(2, up_to_seq);
  q.step();
}

std::int64_t Outbox::unsent_count() const {
  std::lock_guard lock(mu_);
  Query q(db_, path_, "SELECT count(*) FROM shop_outbox WHERE sent = 0");
  q.step();
  return q.col_num(0);
}

std::vector<OutboxEvent> Outbox::after(const std::string& machine, std::int64_t seq, int limit) const {
  std::lock_guard lock(mu_);
  Query q(db_, path_,
          "SELECT seq, at, kind, shop_job, body FROM shop_outbox WHERE machine = ?1 AND seq > ?2 ORDER BY seq LIMIT ?3");
  q.text(1, machine).num(2, seq).num(3, limit);
  std::vector<OutboxEvent> out;
  while (q.step()) out.push_back({q.col_num(0), q.col_text(1), q.col_text(2), q.col_num(3), q.col_text(4)});
  return out;
}

std::int64_t Outbox::cursor(const std::string& consumer, const std::string& machine) const {
  std::lock_guard lock(mu_);
  Query q(db_, path_, "SELECT seq FROM shop_cursors WHERE consumer = ?1 AND machine = ?2");
  q.text(1, consumer).text(2, machine);
  return q.step() ? q.col_num(0) : 0;
}

void Outbox::set_cursor(const std::string& consumer, const std::string& machine, std::int64_t seq) {
  std::lock_guard lock(mu_);
  Query q(db_, path_, "INSERT OR REPLACE INTO shop_cursors (consumer, machine, seq) VALUES (?1, ?2, ?3)");
  q.text(1, consumer).text(2, machine).num(3, seq);
  q.step();
}

void Outbox::link_job(std::int64_t local_id, std::int64_t shop_id, const std::string& machine) {
  std::lock_guard lock(mu_);
  Query q(db_, path_, "INSERT OR REPLACE INTO shop_jobs (local_id, shop_id, machine) VALUES (?1, ?2, ?3)");
  q.num(1, local_id).num(2, shop_id).text(3, machine);
  q.step();
}

std::optional<std::int64_t> Outbox::shop_job_of(std::int64_t local_id) const {
  std::lock_guard lock(mu_);
  Query q(db_, path_, "SELECT shop_id FROM shop_jobs WHERE local_id = ?1");
  q.num(1, local_id);
  if (!q.step()) return std::nullopt;
  return q.col_num(0);
}

std::optional<std::int64_t> Outbox::local_job_of(std::int64_t shop_id) const {
  std::lock_guard lock(mu_);
  Query q(db_, path_, "SELECT local_id FROM shop_jobs WHERE shop_id = ?1 ORDER BY local_id DESC LIMIT 1");
  q.num(1, shop_id);
  if (!q.step()) return std::nullopt;
  return q.col_num(0);
}

}  // namespace cncstream::shop
