#pragma once
// A WebSocket message from a client (docs/api-v1.md, "WebSocket"), checked
// field by field before anything acts on it: the pure half of
// Api::ws_message, which the fuzz targets drive.
#include <nlohmann/json.hpp>

#include <string>
#include <string_view>
#include <vector>

#include "cncstream/daemon/http_types.hpp"
#include "cncstream/protocol/jog.hpp"

namespace cncstream::daemon {

struct WsMessage {
  std::string type;                   // ping, subscribe, jog_start, jog_renew, jog_release
  nlohmann::json id;                  // echoed in the answer; null when absent
  std::vector<std::string> machines;  // subscribe: names, "*" for all
  std::string machine;                // jog_*
  protocol::JogDirection dir;         // jog_start
  double feed = 0;                    // jog_start, mm/min
};

// What the client is answered when its message is refused, with the
// message's id when it had one.
struct WsMessageError {
  ApiError error;
  nlohmann::json id;
};

// Throws WsMessageError (400 bad_request) for malformed JSON, an unknown
// type or a missing or wrong field.
WsMessage parse_ws_message(std::string_view text);

}  // namespace cncstream::daemon
