// A WebSocket text message from a client -> the daemon's checked message
// (parse_ws_message: JSON with a nesting limit, the type, each field), then
// the answer it gets: ack, pong or error with the message's own id, which
// must serialise whatever the client sent.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "cncstream/daemon/ws_message.hpp"

using namespace cncstream::daemon;
using nlohmann::json;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const WsMessage m = parse_ws_message(text);
    if (m.type == "jog_start") {
      // What reaches the jog engine: a finite direction that is not zero, a feed in range.
      double n = 0;
      for (double v : m.dir.v) {
        if (!std::isfinite(v)) std::abort();
        n += std::abs(v);
      }
      if (n == 0 || !(m.feed > 0 && m.feed <= 100000)) std::abort();
    }
    (void)dump_json(json{{"type", m.type == "ping" ? "pong" : "ack"}, {"id", m.id}});
  } catch (const WsMessageError& e) {
    (void)dump_json(json{{"type", "error"}, {"id", e.id}, {"code", e.error.code}, {"message", e.error.message}});
  }
  return 0;
}
