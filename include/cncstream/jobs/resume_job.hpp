#pragma once
// Resume planning (`cncstream resume`): from a journaled job's file lines and
// its last progress, which line to continue after and the preamble that
// brings a reset controller there safely (retract, travel, restore modes,
// spindle and coolant with a dwell, plunge), then the rest of the file. The
// journal and the file's hash check stay with the caller: this takes plain
// values, so it needs neither the transport nor the protocol layer.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "cncstream/gcode/interpreter.hpp"
#include "cncstream/gcode/job_program.hpp"
#include "cncstream/gcode/resume.hpp"
#include "cncstream/geometry/vec3.hpp"
#include "cncstream/jobs/job_control.hpp"

namespace cncstream::jobs {

struct ResumeInput {
  std::filesystem::path file;       // the program the job streamed (for messages and the result)
  std::string file_sha256;          // its hash, checked against the journal by the caller
  std::vector<std::string> lines;   // its lines, as streamed
  // From the journal's last progress row (none: all zero / empty): the last
  // answered 1-based line, and the controller's last reported work position
  // with the last answered line when that report came.
  std::int64_t last_line = 0;
  std::optional<geometry::Vec3> status_work_pos;
  std::int64_t status_line = 0;
  // When the job was itself a resume: the line it continued after. If it
  // answered no file line past it (killed in its preamble, before its first
  // progress row), the same line is where to continue again.
  std::int64_t resumed_after = 0;
  // The controller's planner depth (0: unknown, taken as the deepest of the
  // shipped profiles, grblHAL's 35) and the job's lines answered with an
  // error (the journal's error rows). An error answer stands for up to three
  // motion lines of the program that took no planner block: the line itself,
  // a second one merged into it by a lost end of line, and the next, which
  // may move nowhere on the machine once the failed one did not move (a
  // failed G0 Z2 makes the following G1 Z-1 a zero-length move): the lines
  // the controller may not have run reach that much further back. And a
  // failed line among them never ran although the machine went on past it
  // (the planner ran the lines behind it until the hold stopped it): the
  // resume starts before it.
  int planner_blocks = 0;
  std::vector<std::int64_t> error_lines;
  // The operator's choice: continue after this 1-based line; < 0: chosen from
  // the status report (see gcode::choose_resume_line).
  long from_line = -1;
  std::optional<double> machine_safe_z;  // first G53 G0 Z<this>, machine mm
  std::optional<double> safe_z;          // travel height, work mm; default: the program's highest point
  double plunge_feed = 300;              // mm/min
  double dwell_s = 2;                    // after the spindle starts
};

// What to send, as a stream job takes it.
struct ResumePlan {
  std::filesystem::path file;
  std::string file_sha256;
  std::int64_t total_lines = 0;
  long from_line = 0;                // continue after this 1-based line
  std::string reason;                // why that line, for the operator
  gcode::ParserState state;          // the program's state after that line (tool position, modes)
  // A job program's operation going on after that line (none for other
  // programs): its tool must be in the spindle, touched off at the same Z0.
  std::optional<ProgramOperation> operation;
  gcode::ResumeOptions options;      // with the travel height used
  std::vector<std::string> preamble;
  std::vector<std::string> lines;    // preamble, then the file from line from_line + 1
  std::vector<long> source_lines;    // file line of each: from_line for the preamble
};

// Throws std::invalid_argument when nothing is left to run after the line,
// Cancelled on a stop request.
ResumePlan plan_resume(const ResumeInput& input, const JobControl& control = {});

}  // namespace cncstream::jobs
