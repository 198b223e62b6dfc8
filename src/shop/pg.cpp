#include "cncstream/shop/pg.hpp"

#include <fmt/format.h>
#include <libpq-fe.h>
#include <poll.h>

#include <cerrno>
#include <cstdlib>

namespace cncstream::shop {

std::string redact_url(const std::string& url) {
  // postgresql://user:password@host...: the part between ':' after the scheme's '//' and '@'.
  const auto scheme = url.find("://");
  if (scheme == std::string::npos) {
    // key=value form: password=... up to the next space.
    const auto p = url.find("password=");
    if (p == std::string::npos) return url;
    const auto end = url.find(' ', p);
    return url.substr(0, p) + "password=***" + (end == std::string::npos ? "" : url.substr(end));
  }
  const auto at = url.find('@', scheme + 3);
  if (at == std::string::npos) return url;
  const auto colon = url.find(':', scheme + 3);
  if (colon == std::string::npos || colon > at) return url;
  return url.substr(0, colon + 1) + "***" + url.substr(at);
}

PgResult::PgResult(pg_result* r) : r_(r, PQclear) {}
int PgResult::rows() const { return r_ ? PQntuples(r_.get()) : 0; }
int PgResult::columns() const { return r_ ? PQnfields(r_.get()) : 0; }
bool PgResult::is_null(int row, int col) const { return !r_ || PQgetisnull(r_.get(), row, col); }
std::string PgResult::text(int row, int col) const {
  if (is_null(row, col)) return {};
  return std::string(PQgetvalue(r_.get(), row, col), static_cast<std::size_t>(PQgetlength(r_.get(), row, col)));
}
std::optional<std::string> PgResult::opt(int row, int col) const {
  if (is_null(row, col)) return std::nullopt;
  return text(row, col);
}
std::int64_t PgResult::i64(int row, int col) const {
  return is_null(row, col) ? 0 : std::strtoll(PQgetvalue(r_.get(), row, col), nullptr, 10);
}
double PgResult::f64(int row, int col) const {
  return is_null(row, col) ? 0.0 : std::strtod(PQgetvalue(r_.get(), row, col), nullptr);
}

PgConnection::PgConnection(const std::string& url, double reply_timeout_s) : url_(url), reply_timeout_s_(reply_timeout_s) {
  // Defaults before the URL (libpq: entries before an expanded dbname are
  // overridden by the URL's own): a hub that does not answer fails in 3 s,
  // not after the kernel's TCP time-out, and one that vanished (a pulled
  // cable, a dead PC) is noticed by TCP keepalives after about 2 + 3 x 1 s
  // idle, or 5 s after data it never acknowledged.
  const char* keys[] = {"connect_timeout", "application_name", "keepalives", "keepalives_idle",
                        "keepalives_interval", "keepalives_count", "tcp_user_timeout", "dbname", nullptr};
  const char* values[] = {"3", "cncstream", "1", "2", "1", "3", "5000", url.c_str(), nullptr};
  c_ = PQconnectdbParams(keys, values, 1);
  if (!c_ || PQstatus(c_) != CONNECTION_OK) {
    std::string msg = c_ ? PQerrorMessage(c_) : "out of memory";
    while (!msg.empty() && (msg.back() == '\n' || msg.back() == ' ')) msg.pop_back();
    if (c_) PQfinish(c_);
    c_ = nullptr;
    throw ShopError("shop hub " + redact_url(url) + ": cannot connect: " + msg);
  }
  // Notices (a migration's "already exists, skipping") stay out of the daemon's log.
  PQsetNoticeProcessor(c_, [](void*, const char*) {}, nullptr);
  // Non-blocking sends: a hub that stopped reading cannot hold a send past the reply time-out.
  if (reply_timeout_s_ > 0) PQsetnonblocking(c_, 1);
}

PgConnection::~PgConnection() {
  if (c_) PQfinish(c_);
}

bool PgConnection::ok() const { return c_ && PQstatus(c_) == CONNECTION_OK; }

void PgConnection::drop(const std::string& why) {
  timed_out_ = true;
  PQfinish(c_);
  c_ = nullptr;
  throw ShopError("shop hub " + redact_url(url_) + ": " + why);
}

// Waits for the socket (POLLIN or POLLOUT) until `deadline`; false when it passed.
bool PgConnection::wait_socket(short events, std::chrono::steady_clock::time_point deadline) {
  while (true) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    pollfd fd = {PQsocket(c_), events, 0};
    const int rc = ::poll(&fd, 1, static_cast<int>(left.count()) + 1);
    if (rc > 0) return true;
    if (rc < 0 && errno != EINTR) return true;  // let libpq report the socket's error
  }
}

// The statement sent and its answer awaited for at most the reply time-out:
// a hub that vanished without closing the connection (a half-open TCP
// connection the kernel has not given up on) is noticed then, and the
// connection dropped. Returns PQexec's result: the first failed one, else the last.
pg_result* PgConnection::exec_bounded(const std::string& sql, const PgParams& params) {
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(reply_timeout_s_));
  const std::string silent = fmt::format("the hub did not answer within {} s (the connection is dropped)", reply_timeout_s_);
  int sent = 0;
  if (params.empty()) {
    sent = PQsendQuery(c_, sql.c_str());
  } else {
    std::vector<const char*> values;
    values.reserve(params.size());
    for (const auto& p : params) values.push_back(p ? p->c_str() : nullptr);
    sent = PQsendQueryParams(c_, sql.c_str(), static_cast<int>(params.size()), nullptr, values.data(), nullptr, nullptr, 0);
  }
  if (!sent) return nullptr;  // PQerrorMessage says why
  while (true) {
    const int f = PQflush(c_);
    if (f == 0) break;
    if (f < 0) return nullptr;
    if (!wait_socket(POLLOUT | POLLIN, deadline)) drop(silent);
    if (!PQconsumeInput(c_)) return nullptr;
  }
  pg_result* kept = nullptr;
  while (true) {
    while (PQisBusy(c_)) {
      if (!wait_socket(POLLIN, deadline)) {
        if (kept) PQclear(kept);
        drop(silent);
      }
      if (!PQconsumeInput(c_)) {
        if (kept) PQclear(kept);
        return nullptr;
      }
    }
    pg_result* r = PQgetResult(c_);
    if (!r) return kept;
    const auto failed = [](pg_result* x) {
      const auto st = PQresultStatus(x);
      return st != PGRES_COMMAND_OK && st != PGRES_TUPLES_OK && st != PGRES_EMPTY_QUERY;
    };
    if (kept && failed(kept)) {
      PQclear(r);  // the first failure is the answer; the rest is drained
      continue;
    }
    if (kept) PQclear(kept);
    kept = r;
  }
}

PgResult PgConnection::exec(const std::string& sql, const PgParams& params) {
  sqlstate_.clear();
  error_.clear();
  timed_out_ = false;
  if (!c_) throw ShopError("shop hub " + redact_url(url_) + ": not connected");
  pg_result* r = nullptr;
  if (reply_timeout_s_ > 0) {
    r = exec_bounded(sql, params);
  } else if (params.empty()) {
    r = PQexec(c_, sql.c_str());
  } else {
    std::vector<const char*> values;
    values.reserve(params.size());
    for (const auto& p : params) values.push_back(p ? p->c_str() : nullptr);
    r = PQexecParams(c_, sql.c_str(), static_cast<int>(params.size()), nullptr, values.data(), nullptr, nullptr, 0);
  }
  PgResult res(r);
  const auto st = r ? PQresultStatus(r) : PGRES_FATAL_ERROR;
  if (st != PGRES_COMMAND_OK && st != PGRES_TUPLES_OK) {
    std::string msg = r ? PQresultErrorMessage(r) : PQerrorMessage(c_);
    while (!msg.empty() && (msg.back() == '\n' || msg.back() == ' ')) msg.pop_back();
    if (r) {
      if (const char* s = PQresultErrorField(r, PG_DIAG_SQLSTATE)) sqlstate_ = s;
      if (const char* s = PQresultErrorField(r, PG_DIAG_MESSAGE_PRIMARY)) error_ = s;
    }
    // A connection the server dropped is reset at the next use.
    if (PQstatus(c_) != CONNECTION_OK) {
      PQfinish(c_);
      c_ = nullptr;
    }
    throw ShopError("shop hub " + redact_url(url_) + ": " + msg + (sqlstate_.empty() ? "" : " (SQLSTATE " + sqlstate_ + ")"));
  }
  return res;
}

int PgConnection::socket() const { return c_ ? PQsocket(c_) : -1; }

std::vector<PgNotification> PgConnection::take_notifications() {
  if (!c_) throw ShopError("shop hub " + redact_url(url_) + ": not connected");
  if (!PQconsumeInput(c_) || PQstatus(c_) != CONNECTION_OK) {
    std::string msg = PQerrorMessage(c_);
    while (!msg.empty() && (msg.back() == '\n' || msg.back() == ' ')) msg.pop_back();
    PQfinish(c_);
    c_ = nullptr;
    throw ShopError("shop hub " + redact_url(url_) + ": the connection was lost: " + msg);
  }
  std::vector<PgNotification> out;
  while (PGnotify* n = PQnotifies(c_)) {
    out.push_back({n->relname ? n->relname : "", n->extra ? n->extra : ""});
    PQfreemem(n);
  }
  return out;
}

std::string bytea_hex(const std::string& bytes) {
  static const char* digits = "0123456789abcdef";
  std::string out = "\\x";
  out.reserve(2 + bytes.size() * 2);
  for (unsigned char b : bytes) {
    out.push_back(digits[b >> 4]);
    out.push_back(digits[b & 15]);
  }
  return out;
}

std::string bytes_from_bytea_hex(const std::string& hex) {
  if (hex.size() < 2 || hex[0] != '\\' || hex[1] != 'x' || hex.size() % 2)
    throw ShopError("shop hub: a bytea value is not in hex form");
  auto nib = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    throw ShopError("shop hub: a bytea value has a character that is not hex");
  };
  std::string out;
  out.reserve((hex.size() - 2) / 2);
  for (std::size_t i = 2; i < hex.size(); i += 2) out.push_back(static_cast<char>(nib(hex[i]) * 16 + nib(hex[i + 1])));
  return out;
}

}  // namespace cncstream::shop
