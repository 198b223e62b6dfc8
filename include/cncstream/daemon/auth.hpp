#pragma once
// Who may talk to the daemon: the bearer token (generated at first start,
// stored 0600, compared in constant time), one-shot WebSocket tokens (a
// browser cannot set headers on a WebSocket), and the Origin / Host checks
// that keep a page the operator happens to visit from driving the machine.
#include <chrono>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "cncstream/daemon/config.hpp"
#include "cncstream/daemon/http_types.hpp"

namespace cncstream::daemon {

// Equal length and bytes, in time independent of where they differ.
bool constant_time_equal(const std::string& a, const std::string& b);

// 32 random bytes from the kernel as 64 hex digits.
std::string random_token_hex(std::size_t bytes = 32);

// Reads <data>/token, or creates it (mode 0600) and sets `created`.
// Throws std::runtime_error naming the file when it is unreadable or not
// private (group or others may read it).
std::string load_or_create_token(const std::filesystem::path& data_dir, bool& created);

class Auth {
 public:
  Auth(const DaemonConfig& config, std::string token);
  bool token_required() const { return required_; }
  const std::string& token() const { return token_; }

  // nullopt: allowed; else the error response (401 or 403).
  std::optional<Response> check(const Request& r, bool websocket_upgrade);
  // A one-shot token for a WebSocket upgrade, valid `ttl`.
  std::string issue_ws_token(std::chrono::seconds ttl = std::chrono::seconds(30));

  bool origin_allowed(const Request& r) const;
  bool host_allowed(const Request& r) const;

 private:
  bool consume_ws_token(const std::string& t);
  bool required_;
  std::string token_;
  std::vector<std::string> origins_, hosts_;
  std::mutex mu_;
  std::map<std::string, std::chrono::steady_clock::time_point> ws_tokens_;
};

}  // namespace cncstream::daemon
