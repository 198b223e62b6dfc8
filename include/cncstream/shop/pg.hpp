#pragma once
// A PostgreSQL connection through libpq, blocking, for one thread at a time
// (the shop client's own thread, or a command-line tool). Parameters go as
// text ($1, $2 ...); errors name the hub (its URL without the password) and
// the server's message.
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

struct pg_conn;
struct pg_result;

namespace cncstream::shop {

class ShopError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The URL with any password replaced by "***" (for messages and logs).
std::string redact_url(const std::string& url);

class PgResult {
 public:
  PgResult() = default;
  explicit PgResult(pg_result* r);
  int rows() const;
  int columns() const;
  bool is_null(int row, int col) const;
  std::string text(int row, int col) const;  // "" for NULL
  std::optional<std::string> opt(int row, int col) const;
  std::int64_t i64(int row, int col) const;  // 0 for NULL
  double f64(int row, int col) const;        // 0 for NULL

 private:
  std::shared_ptr<pg_result> r_;
};

using PgParams = std::vector<std::optional<std::string>>;

// A NOTIFY that arrived on a connection that LISTENs.
struct PgNotification {
  std::string channel;
  std::string payload;
};

class PgConnection {
 public:
  // Connects (3 s time-out unless the URL sets connect_timeout; TCP
  // keepalives unless the URL sets them); throws ShopError. `reply_timeout_s`
  // > 0: every exec waits at most this long for the hub's answer, then drops
  // the connection and throws (a hub that vanished without closing it); 0:
  // as long as the hub takes (`cncstream shop init`'s migrations).
  explicit PgConnection(const std::string& url, double reply_timeout_s = 0);
  ~PgConnection();
  PgConnection(const PgConnection&) = delete;
  PgConnection& operator=(const PgConnection&) = delete;

  // Runs one statement (or, without parameters, several); throws ShopError
  // with the server's message and SQLSTATE.
  PgResult exec(const std::string& sql, const PgParams& params = {});
  bool ok() const;
  const std::string& url() const { return url_; }
  // Whether the last exec failed because the hub did not answer within the
  // reply time-out (the connection was dropped).
  bool timed_out() const { return timed_out_; }
  // The SQLSTATE of the last failed exec ("" : none).
  const std::string& last_sqlstate() const { return sqlstate_; }
  // The server's own words for the last failed exec, without the hub or the
  // SQLSTATE (e.g. a function's RAISE EXCEPTION text; "" : none).
  const std::string& last_error() const { return error_; }

  // For a connection that LISTENs: its socket (to poll for reading; -1 when
  // not connected), and the notifications that arrived, reading what the
  // socket holds without blocking. Throws ShopError when the connection is
  // lost (the hub stopped): the connection is then closed.
  int socket() const;
  std::vector<PgNotification> take_notifications();

 private:
  pg_result* exec_bounded(const std::string& sql, const PgParams& params);
  bool wait_socket(short events, std::chrono::steady_clock::time_point deadline);
  [[noreturn]] void drop(const std::string& why);

  pg_conn* c_ = nullptr;
  std::string url_;
  double reply_timeout_s_ = 0;
  bool timed_out_ = false;
  std::string sqlstate_;
  std::string error_;
};

// bytea: PostgreSQL's hex form ("\x...") to bytes and back.
std::string bytea_hex(const std::string& bytes);
std::string bytes_from_bytea_hex(const std::string& hex);

}  // namespace cncstream::shop
