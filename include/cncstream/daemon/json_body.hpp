#pragma once
// JSON from clients (request bodies, WebSocket messages), parsed with a
// nesting limit. nlohmann parses and destroys any depth without recursion,
// but copying, comparing and dumping a value recurse: a WebSocket ping whose
// `id` is an array nested 60,000 deep overflows the stack when the daemon
// echoes it. No message of the API nests deeper than a few levels.
#include <nlohmann/json.hpp>

#include <string_view>

#include "cncstream/daemon/http_types.hpp"

namespace cncstream::daemon {

inline constexpr int kMaxJsonDepth = 32;

// Throws ApiError 400: "malformed JSON at byte N<where>", "a JSON number is
// out of range<where>" (1e500) or "JSON nested deeper than 32 levels<where>"
// (`where` e.g. " of the body", or "").
nlohmann::json parse_json(std::string_view text, std::string_view where);

// A request's JSON body ({} when empty); ApiError 400 naming the byte of a syntax error.
nlohmann::json parse_body(const Request& r);

}  // namespace cncstream::daemon
