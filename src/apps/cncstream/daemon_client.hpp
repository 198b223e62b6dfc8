#pragma once
// A client of the daemon's API v1 (docs/api-v1.md): plain HTTP requests and
// the WebSocket, synchronous and each with a deadline. Boost.Beast stays in
// daemon_client.cpp (it compiles slowly; nothing else needs it).
#include <nlohmann/json.hpp>

#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

namespace cncstream::app {

struct DaemonAddress {
  std::string host;  // "127.0.0.1", "::1", "cnc.local"
  std::string port;  // "8420"
  std::string url() const;          // "http://127.0.0.1:8420"
  std::string host_header() const;  // "127.0.0.1:8420", "[::1]:8420"
};
// "http://127.0.0.1:8420", "127.0.0.1:8420", "http://[::1]:8420/"; throws
// std::invalid_argument naming the text (https is not spoken).
DaemonAddress parse_daemon_address(const std::string& text);
// $CNCSTREAM_DAEMON, else http://127.0.0.1:8420 (the daemon's default).
std::string default_daemon_address();
// The token for a daemon that requires one: $CNCSTREAM_TOKEN (empty: none).
std::string daemon_token_from_env();

// The daemon answered, but not with 2xx: its error body (status, code, message).
class DaemonError : public std::runtime_error {
 public:
  DaemonError(int status, std::string code, const std::string& message)
      : std::runtime_error(message), status_(status), code_(std::move(code)) {}
  int status() const { return status_; }
  const std::string& code() const { return code_; }

 private:
  int status_;
  std::string code_;
};

struct HttpAnswer {
  int status = 0;
  std::string content_type;
  std::string body;
};

class DaemonClient {
 public:
  DaemonClient(DaemonAddress address, std::string client_id, std::string token = {});
  // One request on its own connection. Throws std::runtime_error naming the
  // address when the daemon cannot be reached or does not answer in time.
  HttpAnswer request(const std::string& method, const std::string& target, const std::string& body = {},
                     const std::string& content_type = "application/json", double timeout_s = 10) const;
  // JSON in and out; DaemonError for an answer that is not 2xx.
  nlohmann::json get(const std::string& target, double timeout_s = 10) const;
  nlohmann::json post(const std::string& target, const nlohmann::json& body = nlohmann::json::object(),
                      double timeout_s = 10) const;
  nlohmann::json del(const std::string& target, double timeout_s = 10) const;
  // Raw bytes (a file upload); DaemonError for an answer that is not 2xx.
  nlohmann::json upload(const std::string& target, const std::string& bytes, double timeout_s = 300) const;
  // Text (a program download); DaemonError for an answer that is not 2xx.
  std::string get_text(const std::string& target, double timeout_s = 60) const;

  const DaemonAddress& address() const { return address_; }
  const std::string& client_id() const { return client_id_; }
  const std::string& token() const { return token_; }

 private:
  nlohmann::json json_of(const HttpAnswer& a, const std::string& what) const;
  DaemonAddress address_;
  std::string client_id_;
  std::string token_;
};

// The daemon's WebSocket: JSON messages in both directions.
class DaemonSocket {
 public:
  // Connects and upgrades; throws std::runtime_error naming the address.
  DaemonSocket(const DaemonClient& client, double timeout_s = 5);
  ~DaemonSocket();
  DaemonSocket(const DaemonSocket&) = delete;
  DaemonSocket& operator=(const DaemonSocket&) = delete;
  void send(const nlohmann::json& message, double timeout_s = 5);
  // The next message, or nullopt when none came within timeout_s. Throws
  // std::runtime_error once the socket is closed (saying why).
  std::optional<nlohmann::json> read(double timeout_s);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Percent-encodes a query value.
std::string url_encode(const std::string& text);

// Fields of the daemon's JSON, or the fallback when absent, null or of
// another type (json::value() throws on a key that is present but null).
double num_or(const nlohmann::json& j, const char* key, double fallback);
std::string str_or(const nlohmann::json& j, const char* key, const std::string& fallback = {});
nlohmann::json obj_or(const nlohmann::json& j, const char* key);  // an empty object as the fallback

// A job state the job never leaves (done, failed, stopped, interrupted, cancelled).
bool job_state_is_final(const std::string& state);

}  // namespace cncstream::app
