#pragma once
// Restarting a program after line N on a controller that has been reset (or
// replaced): the G-code that brings it from anywhere to the modal state and
// tool position the program had after line N, safely: retract, travel in XY
// above everything, restore units / distance / plane / WCS / offsets
// (including an active G92), start spindle and coolant with a dwell, plunge
// at the plunge feed, then restore the program's own units, modes and feed.
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "cncstream/gcode/interpreter.hpp"
#include "cncstream/gcode/program.hpp"
#include "cncstream/gcode/line_lexer.hpp"

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
// An arc mode (G2/G3) is left out: GRBL cannot enter it without an arc (a
// bare "G2" is error:26); see with_modal_arc for the line that needs it.
std::vector<std::string> resume_preamble(const ParserState& at, const ResumeOptions& options);

// When the program was in an arc mode after line N, the first line after it
// that moves in the modal mode without naming it must name it itself. Given
// the lines after N and that mode, returns the index of such a line and the
// line with the G word written in front (nullopt: a line names its motion
// before any line relies on the mode, or the mode is no arc).
struct ModalArcFix {
  std::size_t index = 0;
  std::string line;
};
std::optional<ModalArcFix> with_modal_arc(std::span<const std::string> lines_after, MotionMode mode);

// Which line to continue after when the operator does not say. An `ok` only
// means the controller planned a line: GRBL's planner holds up to 15 moves
// it has not made yet, so the last answered line is not where the cut
// stopped. With the controller's last reported work position and the last
// answered line when that report came, the line being cut is the earliest of
// the last `planner_lines` motion lines whose path passes within `tolerance`
// of that position; without a usable report, back off `planner_lines` motion
// lines from the last answered one. Either way some moves may be cut twice
// (harmless: they cut air), none is skipped.
struct ResumeChoice {
  std::size_t after_line = 0;  // continue after this 1-based line (0: from the start)
  std::string reason;          // for the operator
};
struct LastSeen {
  geometry::Vec3 work;                  // work position from the last status report, mm
  std::size_t answered = 0;   // last answered 1-based line when it came
};
ResumeChoice choose_resume_line(const ProgramTrace& trace, std::size_t last_answered,
                                const std::optional<LastSeen>& seen, std::size_t planner_lines = 16,
                                double tolerance = 0.01);

}  // namespace cncstream::gcode
