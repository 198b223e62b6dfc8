#include "cncstream/shop/pg.hpp"

#include <libpq-fe.h>

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

PgConnection::PgConnection(const std::string& url) : url_(url) {
  // The URL's own settings win; a hub that does not answer fails in 3 s,
  // not after the kernel's TCP time-out.
  const char* keys[] = {"dbname", "connect_timeout", "application_name", nullptr};
  const char* values[] = {url.c_str(), "3", "cncstream", nullptr};
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
}

PgConnection::~PgConnection() {
  if (c_) PQfinish(c_);
}

bool PgConnection::ok() const { return c_ && PQstatus(c_) == CONNECTION_OK; }

PgResult PgConnection::exec(const std::string& sql, const PgParams& params) {
  sqlstate_.clear();
  error_.clear();
  if (!c_) throw ShopError("shop hub " + redact_url(url_) + ": not connected");
  pg_result* r = nullptr;
  if (params.empty()) {
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
