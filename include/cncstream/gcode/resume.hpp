#pragma once
// Restarting a program after line N on a controller that has been reset (or
// replaced): the G-code that brings it from anywhere to the modal state and
// tool position the program had after line N, safely: retract, travel in XY
// above everything, restore units / distance / plane / WCS / offsets
// (including an active G92), start spindle and coolant with a dwell, plunge
// at the plunge feed, then restore the program's own units, modes and feed.
#include <optional>
#include <string>
#include <vector>

#include "cncstream/gcode/interpreter.hpp"

namespace cncstream::gcode {

struct ResumeOptions {
  std::optional<double> machine_safe_z;  // first `G53 G0 Z..` (machine mm), if given
  double safe_z = 5;       // retract height in the program's work coordinates, mm
  double plunge_feed = 300;  // mm/min
  double dwell_s = 2;        // after the spindle starts
};

// `at`: the parser state after line N (state_before_line(text, N)), as the
// program's own trace computed it. Every preamble line is plain G-code that
// GRBL 1.1 accepts; coordinates are work coordinates in mm (G21) until the
// last lines restore the program's units.
std::vector<std::string> resume_preamble(const ParserState& at, const ResumeOptions& options);

}  // namespace cncstream::gcode
