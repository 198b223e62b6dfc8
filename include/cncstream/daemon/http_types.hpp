#pragma once
// A request as the API handlers see it and the response they give, free of
// Boost.Beast (which stays in http_server.cpp): the handlers, the router and
// their tests compile without it.
#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cncstream::daemon {

// Joins pieces by appending (GCC 12 warns falsely, -Werror=restrict, on
// "literal" + a temporary std::string).
inline std::string cat(std::initializer_list<std::string_view> parts) {
  std::string s;
  for (auto p : parts) s.append(p);
  return s;
}

// A number as an error message names it: 0.5, 50, 1e+06.
inline std::string num_text(double v) { return fmt::format("{:g}", v); }

// JSON text for a response or a WebSocket frame. Bytes that are not UTF-8 (a
// percent-decoded path, a header, a controller's message) become U+FFFD
// instead of throwing: an answer quoting a client's bytes must not be able
// to take the daemon down (nlohmann's dump() throws on them by default).
inline std::string dump_json(const nlohmann::json& j) {
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

struct Request {
  std::string method;  // "GET", "POST", ...
  std::string path;    // decoded path without the query
  std::map<std::string, std::string> query;    // decoded
  std::map<std::string, std::string> headers;  // names in lower case
  std::string body;                            // JSON requests
  std::filesystem::path body_file;             // uploads: the body spooled to a temporary file
  std::uint64_t body_size = 0;
  std::vector<std::string> params;             // the route's {placeholders}, in order
  std::string client_id;                       // X-Client-Id ("" : none)

  std::string header(const std::string& lower_name) const {
    const auto it = headers.find(lower_name);
    return it == headers.end() ? std::string() : it->second;
  }
  std::optional<std::string> query_value(const std::string& k) const {
    const auto it = query.find(k);
    if (it == query.end()) return std::nullopt;
    return it->second;
  }
};

struct Response {
  int status = 200;
  std::string content_type = "application/json";
  std::string body;
  std::vector<std::pair<std::string, std::string>> headers;
  std::filesystem::path file;  // static files and G-code: sent from this file instead of `body`

  static Response json(int status, const nlohmann::json& j) {
    Response r;
    r.status = status;
    r.body = dump_json(j);
    return r;
  }
  static Response error(int status, const std::string& code, const std::string& message) {
    return json(status, {{"error", {{"status", status}, {"code", code}, {"message", message}}}});
  }
};

// A handler answers now or later: `respond` may be called from any thread
// (it posts to the connection), exactly once.
using Respond = std::function<void(Response)>;

// An error a handler throws; the router turns it into the error body.
struct ApiError {
  int status;
  std::string code;
  std::string message;
};

}  // namespace cncstream::daemon
