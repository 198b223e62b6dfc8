#pragma once
// GRBL-family real-time status report: <State|MPos:..|WCO:..|Bf:..|FS:..|...>.
// Fields may come in any order and most may be missing; the tracker keeps the
// last WCO and override values because they only appear every few reports.
#include <array>
#include <optional>
#include <string>
#include <string_view>

namespace cncstream::protocol {

enum class MachineState { Unknown, Idle, Run, Hold, Jog, Alarm, Door, Check, Home, Sleep, Tool };
const char* to_string(MachineState s);

using Axes = std::array<double, 6>;  // X Y Z A B C; only the first `axis_count` are valid

struct StatusReport {
  MachineState state = MachineState::Unknown;
  int substate = -1;  // Hold:0/1, Door:0-3; -1 when not given
  std::string state_text;  // as received, e.g. "Hold:0"
  int axis_count = 0;
  std::optional<Axes> mpos, wpos, wco;
  std::optional<int> planner_free, rx_free;           // Bf:
  std::optional<double> feed, spindle;                // FS: or F:
  std::optional<std::array<int, 3>> overrides;        // Ov: feed, rapid, spindle %
  std::optional<std::string> pins;                    // Pn:
  std::optional<std::string> accessories;             // A: (S, C, F, M; empty string when A: absent is not told)
  std::optional<long> line_number;                    // Ln:
  std::optional<bool> mpg;                            // grblHAL MPG:0/1
  std::optional<std::string> homed;                   // grblHAL H:
  std::optional<int> tool;                            // grblHAL T:
};

// Parses one `<...>` line. Returns nullopt (and sets `error`) if it is not a
// well-formed status report; unknown fields are ignored, bad numbers are not.
std::optional<StatusReport> parse_status_report(std::string_view line, std::string* error = nullptr);

// Keeps position and override state across reports (WCO and Ov come rarely).
class StatusTracker {
 public:
  // Fills in mpos/wpos from each other with the last known WCO and returns
  // the completed report.
  StatusReport update(StatusReport r);
  const std::optional<StatusReport>& last() const { return last_; }
  const std::optional<Axes>& wco() const { return wco_; }
  const std::optional<std::array<int, 3>>& overrides() const { return ov_; }
  void reset() { *this = StatusTracker{}; }

 private:
  std::optional<StatusReport> last_;
  std::optional<Axes> wco_;
  std::optional<std::array<int, 3>> ov_;
};

}  // namespace cncstream::protocol
