#include "cncstream/jobs/resume_job.hpp"

#include <algorithm>
#include <stdexcept>

#include "cncstream/gcode/program.hpp"
#include "job_run.hpp"

namespace cncstream::jobs {

namespace {
// grblHAL's planner (firmware-profiles/grblhal.toml): the deepest a journal
// that did not record the controller's may have had.
constexpr std::size_t kDeepestPlanner = 35;
}  // namespace

ResumePlan plan_resume(const ResumeInput& in, const JobControl& control) {
  JobRun run(control);
  ResumePlan plan;
  plan.file = in.file;
  plan.file_sha256 = in.file_sha256;
  plan.total_lines = static_cast<std::int64_t>(in.lines.size());

  run.stage("trace", 0, 0.6);
  std::string text;
  for (const auto& l : in.lines) text.append(l).push_back('\n');
  const auto trace = gcode::trace_program(text);

  run.stage("choose line", 0.6, 0.7);
  plan.reason = "--from-line";
  long n = in.from_line;
  if (n < 0 && in.resumed_after > 0 && in.last_line <= in.resumed_after) {
    n = static_cast<long>(in.resumed_after);
    plan.reason = "the job resumed after line " + std::to_string(n) +
                  " and ran no file line past it (it ended in its preamble): continuing there again";
  } else if (n < 0) {
    std::optional<gcode::LastSeen> seen;
    if (in.status_work_pos) seen = gcode::LastSeen{*in.status_work_pos, static_cast<std::size_t>(in.status_line)};
    const std::size_t blocks = in.planner_blocks > 0 ? static_cast<std::size_t>(in.planner_blocks) : kDeepestPlanner;
    const std::size_t window = blocks + 1 + 3 * in.error_lines.size();
    const auto choice = gcode::choose_resume_line(trace, static_cast<std::size_t>(in.last_line), seen, window);
    n = static_cast<long>(choice.after_line);
    plan.reason = choice.reason;
    // A line that failed near the end never ran, though the machine may have
    // gone on past it. (One further back was passed over on purpose: the
    // job went on after it.)
    for (const std::int64_t e : in.error_lines) {
      if (e > n || in.last_line - e >= static_cast<std::int64_t>(window)) continue;  // runs again anyway, or long passed
      n = static_cast<long>(e) - 1;
      plan.reason += "; line " + std::to_string(e) + " was answered with an error and never ran: it runs again";
    }
  }
  if (n >= plan.total_lines)
    throw std::invalid_argument("--from-line " + std::to_string(n) + ": " + in.file.string() + " has only " +
                                std::to_string(plan.total_lines) + " lines; nothing left to run");
  plan.from_line = n;
  plan.operation = operation_after_line(program_operations(in.lines), static_cast<std::size_t>(n));

  run.stage("state", 0.7, 0.95);
  plan.state = gcode::state_before_line(text, static_cast<std::size_t>(n));
  gcode::ResumeOptions& ro = plan.options;
  ro.machine_safe_z = in.machine_safe_z;
  ro.plunge_feed = in.plunge_feed;
  ro.dwell_s = in.dwell_s;
  if (in.safe_z) {
    ro.safe_z = *in.safe_z;
  } else {
    // The program's own highest point (its retract height) clears everything it cuts.
    double top = plan.state.work_position().z;
    for (const auto& s : trace.segments) top = std::max({top, s.work_from().z, s.work_to().z});
    ro.safe_z = top;
  }

  run.stage("preamble", 0.95, 1.0);
  plan.preamble = gcode::resume_preamble(plan.state, ro);
  for (const auto& l : plan.preamble) {
    plan.lines.push_back(l);
    plan.source_lines.push_back(n);
  }
  const std::size_t first = plan.lines.size();
  for (long k = n; k < plan.total_lines; ++k) {
    plan.lines.push_back(in.lines[static_cast<std::size_t>(k)]);
    plan.source_lines.push_back(k + 1);
  }
  // An arc mode the preamble could not restore: the first line moving in it names it.
  if (plan.state.modal.motion == gcode::MotionMode::ArcCW || plan.state.modal.motion == gcode::MotionMode::ArcCCW) {
    const std::span<const std::string> after(plan.lines.data() + first, plan.lines.size() - first);
    if (const auto fix = gcode::with_modal_arc(after, plan.state.modal.motion)) plan.lines[first + fix->index] = fix->line;
  }
  run.finish();
  return plan;
}

}  // namespace cncstream::jobs
