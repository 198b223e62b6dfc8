// `cncstream resume JOB [PORT] [--from-line N]`: continue a journaled job after
// line N (default: the line the machine was cutting when the job ended, from
// the journaled status report; see choose_resume_line). The file must be
// the one the job streamed (same SHA-256). The resume job (jobs/resume_job.hpp)
// plans it: the modal state at line N from the program itself through the
// G-code interpreter, a preamble that brings the controller there safely, then
// the file from line N+1. Never automatic: the operator confirms the plan (or
// passes --yes).
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

#include "cncstream/gcode/gcode_writer.hpp"
#include "cncstream/gcode/interpreter.hpp"
#include "cncstream/jobs/resume_job.hpp"
#include "cncstream/transport/journal.hpp"
#include "cncstream/transport/sha256.hpp"
#include "commands.hpp"
#include "job_session.hpp"

namespace cncstream::app {

void register_resume(CLI::App& app, CommandRegistry& registry) {
  struct Opts {
    long long job = 0;
    long from_line = -1;
    std::optional<double> machine_safe_z, safe_z;
    double plunge_feed = 300, dwell = 2;
    ConnectionOptions conn;
    SimCliOptions sim;
  };
  auto o = std::make_shared<Opts>();
  auto* sub = app.add_subcommand("resume", "Continue a journaled job after line N (after homing / a disconnect)");
  sub->add_option("job", o->job, "Journal job id (see `cncstream jobs`)")->required();
  sub->add_option("port", o->conn.port, "Serial port, 'auto' or 'sim'")->capture_default_str();
  sub->add_option("--from-line", o->from_line, "Continue after this file line (default: before the line the machine was last seen cutting)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--safe-z-machine", o->machine_safe_z, "Retract first with G53 G0 Z<this> (machine coordinates)");
  sub->add_option("--safe-z", o->safe_z, "Travel height in work coordinates (default: the program's highest point)");
  sub->add_option("--plunge-feed", o->plunge_feed, "Feed for the plunge back to the cut, mm/min")
      ->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--dwell", o->dwell, "Seconds to wait after the spindle starts")->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  add_connection_options(sub, o->conn);
  add_sim_options(sub, o->sim);
  registry.add(sub, [o] {
    const auto jpath = journal_path(o->conn);
    if (!std::filesystem::exists(jpath)) throw std::invalid_argument("no journal at " + jpath.string());
    std::optional<transport::JobRecord> rec;
    std::optional<transport::ProgressRecord> last;
    std::vector<std::int64_t> error_lines;
    std::vector<transport::ToolChangeRow> tool_changes;
    {
      transport::Journal j(jpath);
      rec = j.job(o->job);
      if (!rec) throw std::invalid_argument("no job " + std::to_string(o->job) + " in " + jpath.string());
      last = j.last_progress(o->job);
      error_lines = j.progress_lines(o->job, "error");
      tool_changes = j.tool_changes(o->job);
    }
    const std::filesystem::path file = rec->file;
    if (!std::filesystem::exists(file))
      throw std::invalid_argument("job " + std::to_string(o->job) + ": its file " + file.string() + " is gone");
    const std::string sha = transport::sha256_file(file);
    if (sha != rec->file_sha256)
      throw std::invalid_argument(file.string() + " changed since job " + std::to_string(o->job) +
                                  " streamed it (SHA-256 " + sha.substr(0, 16) + "..., journal " +
                                  rec->file_sha256.substr(0, 16) + "...): refusing to resume a different program");
    session::JobInput whole = session::job_from_file(file);
    jobs::ResumeInput in;
    in.file = file;
    in.file_sha256 = sha;
    in.lines = std::move(whole.lines);
    if (last) {
      in.last_line = last->last_line;
      if (last->status_work_pos)
        in.status_work_pos = geometry::Vec3{(*last->status_work_pos)[0], (*last->status_work_pos)[1], (*last->status_work_pos)[2]};
      in.status_line = last->status_line;
    }
    if (rec->resumed_from > 0) in.resumed_after = rec->from_line;
    in.planner_blocks = static_cast<int>(rec->planner_blocks);
    in.error_lines = std::move(error_lines);
    in.from_line = o->from_line;
    in.machine_safe_z = o->machine_safe_z;
    in.safe_z = o->safe_z;
    in.plunge_feed = o->plunge_feed;
    in.dwell_s = o->dwell;
    jobs::ResumePlan plan = jobs::plan_resume(in);
    const long n = plan.from_line;
    const gcode::ParserState& at = plan.state;
    const gcode::ResumeOptions& ro = plan.options;
    const auto& preamble = plan.preamble;

    session::JobInput job;
    job.file = plan.file;
    job.file_sha256 = plan.file_sha256;
    job.total_lines = plan.total_lines;
    job.resumed_from = o->job;
    job.from_line = n;
    job.lines = std::move(plan.lines);
    job.source_lines = std::move(plan.source_lines);
    const auto limits = planning_limits(o->conn, o->sim);
    EtaEstimator eta = estimate_job(job, limits, planning_link(o->conn, o->sim));
    const geometry::Vec3 p = at.work_position();
    std::cout << "resume job " << rec->id << " (" << rec->outcome.value_or("interrupted") << "): " << file.string()
              << "\n  continue after line " << n << " of " << whole.total_lines << " (last answered: "
              << (last ? std::to_string(last->last_line) : std::string("none")) << ")\n"
              << "  why line " << n << ": " << plan.reason << "\n"
              << "  tool at line " << n << ": X" << format_gcode_number(p.x) << " Y" << format_gcode_number(p.y)
              << " Z" << format_gcode_number(p.z) << " (work), " << gcode::format_modes(at) << "\n"
              << (plan.operation ? "  in operation " + std::to_string(plan.operation->number) + " (" +
                                       plan.operation->name + "): T" + std::to_string(plan.operation->tool) + ", " +
                                       plan.operation->cutter +
                                       " must be in the spindle, touched off at the same Z0 as before\n"
                                 : std::string())
              << (tool_changes.empty()
                      ? std::string()
                      : "  the journal's last tool change (line " + std::to_string(tool_changes.back().line) + "): T" +
                            std::to_string(tool_changes.back().tool) + " in the spindle, its length " +
                            (tool_changes.back().length_known ? "measured (" + tool_changes.back().method + ")"
                                                              : std::string("UNKNOWN: measure it and set work Z before "
                                                                            "resuming")) +
                            "\n")
              << "  the controller must be homed with the same work offset as before\n"
              << "  preamble (retract to Z" << format_gcode_number(ro.safe_z) << ", travel, restore, plunge at F"
              << format_gcode_number(ro.plunge_feed) << "):\n";
    for (const auto& l : preamble) std::cout << "    " << l << "\n";
    std::cout << "  estimated machining time: " << format_duration(eta.total()) << std::endl;
    if (!confirm("Resume on " + o->conn.port + "?", o->conn.yes)) return 2;
    return run_session(o->conn, o->sim, job, std::nullopt, std::move(eta));
  });
}

}  // namespace cncstream::app
