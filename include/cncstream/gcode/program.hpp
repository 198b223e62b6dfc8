#pragma once
// Whole-program helpers on top of the interpreter: trace a G-code file into
// straight path segments (arcs chorded like the firmware), find the modal
// state before any line (resume from line N), and estimate run time.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "cncstream/gcode/interpreter.hpp"
#include "cncstream/gcode/motion_planner.hpp"
#include "cncstream/gcode/stream_link.hpp"

namespace cncstream::gcode {

struct PathSegment {
  geometry::Vec3 from, to;           // machine coordinates, mm
  geometry::Vec3 wco;                // work offset in force: work = machine - wco
  bool rapid = false;
  double feed = 0;         // mm/min (0 for rapids)
  std::size_t source_line = 0;  // 0-based line index in the program text
  geometry::Vec3 work_from() const { return from - wco; }
  geometry::Vec3 work_to() const { return to - wco; }
};

struct LineError {
  std::size_t line = 0;  // 0-based
  int status = 0;        // GRBL error code
  std::string text;      // the raw line
  // "line 12: error:22: G1 X1"; the firmware profile's error_info() says
  // what error:22 means.
  std::string message() const;
};

struct ProgramOptions {
  ParserState initial;
  double arc_tolerance = 0.002;  // $12
  bool stop_at_first_error = false;
};

struct ProgramTrace {
  std::vector<PathSegment> segments;
  std::vector<LineError> errors;
  double dwell_seconds = 0;
  std::size_t lines = 0;
  // Per line (0-based): the bytes a streamer sends for it (cleaned length +
  // 1), 0 for a line that is not sent (empty after cleaning, '%').
  std::vector<std::uint32_t> line_bytes;
  ParserState final_state;
};

// Lines that are empty after cleaning, "%" lines and '$' system lines are
// skipped (they carry no motion); any other line is interpreted.
ProgramTrace trace_program(std::string_view text, const ProgramOptions& options = {});

// The parser state just before 0-based line `line` runs (after lines [0, line)).
// Lines with errors are skipped, as the firmware would leave the state.
ParserState state_before_line(std::string_view text, std::size_t line,
                              const ParserState& initial = {});

std::vector<MotionBlock> to_motion_blocks(const std::vector<PathSegment>& segments);

struct TimeEstimate {
  double motion_seconds = 0;
  double dwell_seconds = 0;
  double total() const { return motion_seconds + dwell_seconds; }
};
TimeEstimate estimate_program_time(const ProgramTrace& trace, const MotionLimits& limits);
// The same over a link: a line reaches the planner only once its bytes have
// crossed the wire, which carries them only while the RX buffer has room
// (character counting), and the planner holds link.planner_blocks. A program
// whose moves are shorter than the wire delivers at their feed takes the
// wire's time, not the motion's. An unbounded link gives the estimate above.
TimeEstimate estimate_program_time(const ProgramTrace& trace, const MotionLimits& limits, const StreamLink& link);

// When each line's motion is done, in seconds from the start, through the
// same planner as estimate_motion_time: entry i is for 0-based line i (a line
// without motion gets the time of the motion before it). `line_count`
// entries; the last one is the total motion time. Dwells are not included.
std::vector<double> estimate_line_end_times(const ProgramTrace& trace, const MotionLimits& limits,
                                            std::size_t line_count);
// The same over a link (see estimate_program_time).
std::vector<double> estimate_line_end_times(const ProgramTrace& trace, const MotionLimits& limits,
                                            std::size_t line_count, const StreamLink& link);

// Splits text into lines at '\n' (a trailing '\r' is kept; cleaning drops it).
std::vector<std::string_view> split_lines(std::string_view text);

}  // namespace cncstream::gcode
