// `cncstream resume JOB [PORT] [--from-line N]`: continue a journaled job after
// line N (default: the line the machine was cutting when the job ended, from
// the journaled status report; see choose_resume_line). The file must be
// the one the job streamed (same SHA-256). The modal state at line N comes
// from the program itself through the G-code interpreter; a preamble brings
// the controller there safely, then the file continues with line N+1. Never
// automatic: the operator confirms the plan (or passes --yes).
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

#include "cncstream/gcode/gcode_writer.hpp"
#include "cncstream/gcode/program.hpp"
#include "cncstream/gcode/resume.hpp"
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
    {
      transport::Journal j(jpath);
      rec = j.job(o->job);
      if (!rec) throw std::invalid_argument("no job " + std::to_string(o->job) + " in " + jpath.string());
      last = j.last_progress(o->job);
    }
    const std::filesystem::path file = rec->file;
    if (!std::filesystem::exists(file))
      throw std::invalid_argument("job " + std::to_string(o->job) + ": its file " + file.string() + " is gone");
    const std::string sha = transport::sha256_file(file);
    if (sha != rec->file_sha256)
      throw std::invalid_argument(file.string() + " changed since job " + std::to_string(o->job) +
                                  " streamed it (SHA-256 " + sha.substr(0, 16) + "..., journal " +
                                  rec->file_sha256.substr(0, 16) + "...): refusing to resume a different program");
    const session::JobInput whole = session::job_from_file(file);
    std::string text;
    for (const auto& l : whole.lines) text.append(l).push_back('\n');
    const auto trace = gcode::trace_program(text);
    std::string why = "--from-line";
    long n = o->from_line;
    if (n < 0) {
      std::optional<gcode::LastSeen> seen;
      if (last && last->status_work_pos)
        seen = gcode::LastSeen{{(*last->status_work_pos)[0], (*last->status_work_pos)[1], (*last->status_work_pos)[2]},
                               static_cast<std::size_t>(last->status_line)};
      const auto choice =
          gcode::choose_resume_line(trace, last ? static_cast<std::size_t>(last->last_line) : 0, seen);
      n = static_cast<long>(choice.after_line);
      why = choice.reason;
    }
    if (n >= whole.total_lines)
      throw std::invalid_argument("--from-line " + std::to_string(n) + ": " + file.string() + " has only " +
                                  std::to_string(whole.total_lines) + " lines; nothing left to run");

    const gcode::ParserState at = gcode::state_before_line(text, static_cast<std::size_t>(n));
    gcode::ResumeOptions ro;
    ro.machine_safe_z = o->machine_safe_z;
    ro.plunge_feed = o->plunge_feed;
    ro.dwell_s = o->dwell;
    if (o->safe_z) {
      ro.safe_z = *o->safe_z;
    } else {
      // The program's own highest point (its retract height) clears everything it cuts.
      double top = at.work_position().z;
      for (const auto& s : trace.segments) top = std::max({top, s.work_from().z, s.work_to().z});
      ro.safe_z = top;
    }
    const auto preamble = gcode::resume_preamble(at, ro);

    session::JobInput job;
    job.file = file;
    job.file_sha256 = sha;
    job.total_lines = whole.total_lines;
    job.resumed_from = o->job;
    job.from_line = n;
    for (const auto& l : preamble) {
      job.lines.push_back(l);
      job.source_lines.push_back(n);
    }
    for (long k = n; k < whole.total_lines; ++k) {
      job.lines.push_back(whole.lines[static_cast<std::size_t>(k)]);
      job.source_lines.push_back(k + 1);
    }
    const auto limits = planning_limits(o->conn, o->sim);
    EtaEstimator eta = estimate_job(job, limits);
    const Vec3 p = at.work_position();
    std::cout << "resume job " << rec->id << " (" << rec->outcome.value_or("interrupted") << "): " << file.string()
              << "\n  continue after line " << n << " of " << whole.total_lines << " (last answered: "
              << (last ? std::to_string(last->last_line) : std::string("none")) << ")\n"
              << "  why line " << n << ": " << why << "\n"
              << "  tool at line " << n << ": X" << format_gcode_number(p.x) << " Y" << format_gcode_number(p.y)
              << " Z" << format_gcode_number(p.z) << " (work), " << gcode::format_modes(at) << "\n"
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
