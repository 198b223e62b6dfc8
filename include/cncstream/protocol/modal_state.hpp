#pragma once
// The modal state a restart needs, followed line by line as the controller
// answers them. It is the G-code interpreter's own state (gcode::ParserState):
// one modal state for the project, not a second tracker.
#include <string_view>

#include "cncstream/gcode/interpreter.hpp"

namespace cncstream::protocol {

// Applies a line the controller accepted. A line the interpreter does not
// know (a firmware's own M-code, a `$` command) leaves the state unchanged.
void apply_answered_line(gcode::ParserState& state, std::string_view line);

}  // namespace cncstream::protocol
