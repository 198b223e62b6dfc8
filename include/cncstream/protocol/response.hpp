#pragma once
// Classifies one line received from a controller. Pure: no profile knowledge
// except what the line itself says (banners are matched by the session,
// because they depend on the firmware profiles).
#include <optional>
#include <string>
#include <string_view>

#include "cncstream/protocol/status_report.hpp"

namespace cncstream::protocol {

enum class ResponseKind {
  Empty,
  Ok,            // "ok" (Marlin may add " N.. P.. B..")
  Error,         // "error:N" (GRBL family)
  Alarm,         // "ALARM:N"
  Status,        // "<...>"
  Message,       // "[MSG:...]"
  ParserState,   // "[GC:...]"
  Version,       // "[VER:...]"
  Options,       // "[OPT:...]"
  Feedback,      // any other "[...]" (e.g. [G54:..], [PRB:..], [FIRMWARE:..], [echo:..])
  StartupEcho,   // ">G54:ok" startup-line execution report
  Resend,        // Marlin "Resend: n" / "rs n"
  MarlinError,   // Marlin "Error:..." / "!! ..."
  Busy,          // Marlin "echo:busy: processing"
  Other,         // anything else (banners, echo:, Marlin chatter)
};
const char* to_string(ResponseKind k);

struct Response {
  ResponseKind kind = ResponseKind::Empty;
  std::string line;        // as received, without CR/LF
  std::string body;        // payload: "[MSG:body]", "error:N" -> "N", ...
  int code = 0;            // error / alarm number, resend line
  std::optional<StatusReport> status;
  // Marlin advanced ok: "ok N<line> P<planner free> B<buffer free>".
  std::optional<long> ok_line;
  std::optional<int> ok_planner_free, ok_buffer_free;
  std::string parse_error;  // set when a line looked like a known form but was malformed
};

Response parse_response(std::string_view line);

// [OPT:flags,blocks,rx(,axes...)] -> planner blocks and RX bytes.
struct BuildOptions {
  std::string flags;
  std::optional<int> planner_blocks;
  std::optional<int> rx_buffer_size;
};
std::optional<BuildOptions> parse_build_options(std::string_view opt_body);

// Splits a byte stream into lines; accepts LF, CRLF and CR endings.
class LineSplitter {
 public:
  // Appends bytes; returns the completed lines (without terminators).
  template <class F>
  void feed(std::string_view bytes, F&& on_line) {
    for (char c : bytes) {
      if (c == '\n' || c == '\r') {
        if (!partial_.empty()) on_line(std::string_view(partial_));
        partial_.clear();
      } else if (partial_.size() < kMaxLine) {
        partial_.push_back(c);
      }
    }
  }
  const std::string& partial() const { return partial_; }
  void clear() { partial_.clear(); }

 private:
  static constexpr std::size_t kMaxLine = 4096;  // a runaway line cannot grow without bound
  std::string partial_;
};

}  // namespace cncstream::protocol
