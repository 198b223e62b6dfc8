#pragma once
// The jog mode's display as pure formatting: a DroView (state in) -> one
// line (out). The terminal edge (cmd_jog.cpp) redraws it in place on a TTY
// and prints it as plain lines otherwise.
#include <optional>
#include <string>

#include "cncstream/protocol/status_report.hpp"

namespace cncstream::app {

struct DroView {
  std::string link;   // "ready", "connecting", "disconnected", ...
  std::string state;  // the controller's state ("Idle", "Jog", "Alarm"); "" before the first report
  std::optional<protocol::Axes> wpos, mpos;
  double step_mm = 0;
  double feed_mm_min = 0;
  std::string jog;      // "X+ held", "" when no key is held
  std::string message;  // the last result or refusal
};

// "Idle | WPos X   0.100 Y   0.000 Z   0.000 | MPos ... | step 0.100 mm | feed 500 mm/min | X+ held | msg",
// cut to `width` columns (0: no limit). A link other than ready replaces the state.
std::string format_dro_line(const DroView& v, int width = 0);
// A step size for the display: "0.01", "0.1", "1", "10".
std::string format_step(double mm);
// The jog mode's keys, one line.
const char* jog_keys_help();

}  // namespace cncstream::app
