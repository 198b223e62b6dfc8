#pragma once
// A whole job in one program: several operations, each with its own tool.
// The header (units, modes) is written once; each operation begins with its
// tool (T word, spindle on, dwell) and, from the second on, a tool change:
// spindle off, retract to the safe Z, a comment naming the tool to mount and
// how, then M0 (GRBL has no M6: the program pauses, the operator changes the
// tool and resumes with cycle start) or M6 where the controller has one.
// Bodies are written by the operations' own writers (pieces, roughing ...)
// into writer(); the totals of every body are summed into stats().
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/gcode/finishing_program.hpp"
#include "cncstream/gcode/gcode_writer.hpp"

namespace cncstream {

enum class ToolChangeCode { PauseM0, M6 };

struct JobProgramOptions {
  int decimals = 3;
  double safe_z = 5;  // work coordinates; every tool change retracts here
  double dwell_s = 2;  // spindle spin-up after each M3
  std::vector<std::string> header_comments;
  ToolChangeCode tool_change = ToolChangeCode::PauseM0;
};

struct OperationHeader {
  std::string name;  // "roughing", "finishing", ...
  int tool = 1;      // T number
  cam::Cutter cutter;
  double rpm = 18000;  // 0: no spindle commands
};

// The comment written before a tool change's M0/M6 (also what a streamer
// shows the operator when the program pauses there).
std::string tool_change_message(const OperationHeader& op);

// An operation of a job program read back from its lines: the comment
// begin_operation writes ("operation 2: finishing with T2, 3.175 mm
// ball-nose end mill [ball:3.175]", wrapped or not) and its tool change.
struct ProgramOperation {
  int number = 0;
  std::string name;
  int tool = 0;
  std::string cutter;  // "3.175 mm ball-nose end mill [ball:3.175]"
  std::size_t first_line = 0;    // 1-based: its comment
  // 1-based: from this line on its tool is in the spindle (its tool
  // change's M0/M6; its comment where it needs none: the first operation,
  // or the same tool going on).
  std::size_t mounted_line = 0;
};

// In program order; empty for a program not written by JobProgram.
std::vector<ProgramOperation> program_operations(const std::vector<std::string>& lines);
std::vector<ProgramOperation> program_operations(std::span<const std::string_view> lines);

// The operation whose tool is in the spindle once `line` (1-based; 0:
// none yet) has run: the first operation up to its own tool change.
// Empty for a program without operations.
std::optional<ProgramOperation> operation_after_line(const std::vector<ProgramOperation>& ops, std::size_t line);

class JobProgram {
 public:
  explicit JobProgram(JobProgramOptions options);

  // Starts an operation: its comment, the tool change (from the second
  // operation on, unless it names the tool already in), T, spindle and
  // dwell. The tool is left at the safe Z.
  void begin_operation(const OperationHeader& op);
  GcodeWriter& writer() { return w_; }
  ProgramStats& stats() { return stats_; }
  int operations() const { return operations_; }

  // Spindle off, program end; the text of the whole program. stats().lines
  // and motion_lines are filled in.
  std::string finish();

 private:
  JobProgramOptions opt_;
  GcodeWriter w_;
  ProgramStats stats_;
  void begin_spindle(double rpm);

  int operations_ = 0;
  int tool_ = 0;
  bool spindle_on_ = false;
};

}  // namespace cncstream
