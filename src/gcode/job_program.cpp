#include "cncstream/gcode/job_program.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace cncstream {

std::string tool_change_message(const OperationHeader& op) {
  return fmt::format(
      "TOOL CHANGE for {}: mount T{}, {} [{}]. Z0 must stay where it was set (the part's top surface or "
      "the same reference): touch off the new tool there, then resume with cycle start",
      op.name, op.tool, op.cutter.description(), op.cutter.spec());
}

JobProgram::JobProgram(JobProgramOptions options) : opt_(std::move(options)), w_(opt_.decimals) {
  if (!std::isfinite(opt_.safe_z)) throw std::invalid_argument("safe Z must be a finite number");
  for (const auto& c : opt_.header_comments) w_.comment(c);
  w_.line("G21 G90 G17 G94");  // mm, absolute, XY plane, units/min feed
}

void JobProgram::begin_operation(const OperationHeader& op) {
  if (op.tool < 1) throw std::invalid_argument(fmt::format("operation {}: tool number {} is not positive", op.name, op.tool));
  if (!(op.rpm >= 0)) throw std::invalid_argument(fmt::format("operation {}: spindle speed must not be negative", op.name));
  ++operations_;
  w_.comment(fmt::format("operation {}: {} with T{}, {} [{}]", operations_, op.name, op.tool, op.cutter.description(),
                         op.cutter.spec()));
  if (operations_ > 1 && op.tool == tool_) {
    // The same tool goes on: no pause, the spindle keeps turning.
    if (op.rpm > 0 && !spindle_on_) begin_spindle(op.rpm);
    w_.rapid(std::nullopt, std::nullopt, opt_.safe_z);
    return;
  }
  tool_ = op.tool;
  if (operations_ > 1) {
    // The previous operation ended at the safe Z; say it again, the
    // operator's hands are about to be near the tool.
    if (spindle_on_) w_.line("M5");
    spindle_on_ = false;
    w_.rapid(std::nullopt, std::nullopt, opt_.safe_z);
    w_.comment(tool_change_message(op));
  }
  w_.line(fmt::format("T{}", op.tool));
  if (operations_ > 1) {
    w_.line(opt_.tool_change == ToolChangeCode::M6 ? "M6" : "M0");
    // After a pause the writer cannot know what the operator did (a
    // controller keeps its modal state, but a reset would not): write the
    // next move in full.
    w_.reset_modal();
    w_.line("G21 G90 G17 G94");
  }
  if (op.rpm > 0) begin_spindle(op.rpm);
  w_.rapid(std::nullopt, std::nullopt, opt_.safe_z);
}

void JobProgram::begin_spindle(double rpm) {
  w_.line("M3 S" + format_gcode_number(rpm, 0));
  spindle_on_ = true;
  if (opt_.dwell_s > 0) w_.line("G4 P" + format_gcode_number(opt_.dwell_s, 2));
}

std::string JobProgram::finish() {
  if (operations_ == 0) throw std::invalid_argument("a job program needs at least one operation");
  w_.rapid(std::nullopt, std::nullopt, opt_.safe_z);
  if (spindle_on_) w_.line("M5");
  spindle_on_ = false;
  w_.line("M2");
  stats_.lines = w_.lines().size();
  stats_.motion_lines = w_.motion_lines();
  return w_.text();
}

}  // namespace cncstream
