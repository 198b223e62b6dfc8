#include "cncstream/gcode/job_program.hpp"

#include <fmt/format.h>

#include <cmath>
#include <string_view>
#include <stdexcept>

namespace cncstream {

std::string tool_change_message(const OperationHeader& op) {
  return fmt::format(
      "TOOL CHANGE for {}: mount T{}, {} [{}]. Z0 must stay where it was set (the part's top surface or "
      "the same reference): touch off the new tool there, then resume with cycle start",
      op.name, op.tool, op.cutter.description(), op.cutter.spec());
}

namespace {

// The text inside a whole-line comment "(...)"; empty when the line is not one.
std::string_view comment_text(std::string_view line) {
  if (line.size() < 2 || line.front() != '(' || line.back() != ')') return {};
  return line.substr(1, line.size() - 2);
}

bool is_pause(std::string_view line) { return line == "M0" || line == "M6"; }

// "2: finishing with T2, 3.175 mm ball-nose end mill [ball:3.175]"
std::optional<ProgramOperation> parse_operation(const std::string& text) {
  ProgramOperation op;
  const auto colon = text.find(": ");
  const auto with = text.find(" with T", colon == std::string::npos ? 0 : colon);
  if (colon == std::string::npos || with == std::string::npos) return std::nullopt;
  const auto comma = text.find(", ", with);
  if (comma == std::string::npos) return std::nullopt;
  try {
    std::size_t used = 0;
    op.number = std::stoi(text.substr(0, colon), &used);
    if (used != colon) return std::nullopt;
    op.tool = std::stoi(text.substr(with + 7, comma - with - 7), &used);
    if (used != comma - with - 7) return std::nullopt;
  } catch (const std::exception&) {
    return std::nullopt;
  }
  op.name = text.substr(colon + 2, with - colon - 2);
  op.cutter = text.substr(comma + 2);
  return op;
}

}  // namespace

namespace {

template <class Lines>
std::vector<ProgramOperation> operations_of(const Lines& lines) {
  constexpr std::string_view kOperation = "operation ";
  std::vector<ProgramOperation> ops;
  for (std::size_t k = 0; k < lines.size(); ++k) {
    const std::string_view c = comment_text(lines[k]);
    if (c.substr(0, kOperation.size()) != kOperation) continue;
    // A long comment goes on in the next comment lines, up to the cutter's "[spec]".
    std::string text(c.substr(kOperation.size()));
    for (std::size_t m = k + 1; !text.empty() && text.back() != ']' && m < lines.size() && m <= k + 3; ++m) {
      const std::string_view more = comment_text(lines[m]);
      if (more.empty()) break;
      text.append(" ").append(more);
    }
    auto op = parse_operation(text);
    if (!op) continue;
    op->first_line = k + 1;
    op->mounted_line = k + 1;
    if (!ops.empty() && ops.back().tool != op->tool)
      // Its tool change: the pause after the comment, before the first move.
      for (std::size_t m = k + 1; m < lines.size() && m <= k + 16; ++m)
        if (is_pause(lines[m])) {
          op->mounted_line = m + 1;
          break;
        }
    ops.push_back(std::move(*op));
  }
  return ops;
}

}  // namespace

std::vector<ProgramOperation> program_operations(const std::vector<std::string>& lines) { return operations_of(lines); }
std::vector<ProgramOperation> program_operations(std::span<const std::string_view> lines) {
  return operations_of(lines);
}

std::optional<ProgramOperation> operation_after_line(const std::vector<ProgramOperation>& ops, std::size_t line) {
  if (ops.empty()) return std::nullopt;
  ProgramOperation in = ops.front();
  for (const auto& op : ops)
    if (op.mounted_line <= line) in = op;
  return in;
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
