// `cncstream FILE PORT [options]` (also `cncstream stream FILE PORT`): stream a
// G-code file, or machine an STL: generate the finishing path, show the plan,
// confirm, stream. PORT may be a device, `auto`, or `sim` (built-in simulator).
// Ctrl-C or `s` asks for a controlled stop (hold, wait, soft reset). When a
// running daemon owns PORT, the job is handed to it (daemon_handoff.hpp).
#include <algorithm>
#include <fstream>
#include <iostream>
#include <memory>

#include "cncstream/gcode/gcode_writer.hpp"
#include "cncstream/jobs/output_file.hpp"
#include "cncstream/jobs/toolpath_job.hpp"
#include "cncstream/transport/sha256.hpp"
#include "commands.hpp"
#include "daemon_handoff.hpp"
#include "job_session.hpp"
#include "long_job.hpp"
#include "tool_choice.hpp"
#include "toolpath_options.hpp"

namespace cncstream::app {

namespace {

bool is_stl(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (auto& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return ext == ".stl";
}

// Where a generated program is kept: next to the journal, named by the part
// and the program's hash, so `cncstream resume` finds the same bytes again.
std::filesystem::path program_path(const ConnectionOptions& c, const std::string& stl, const std::string& sha) {
  const auto dir = journal_path(c).parent_path() / "programs";
  std::filesystem::create_directories(dir);
  return dir / (std::filesystem::path(stl).stem().string() + "-" + sha.substr(0, 12) + ".nc");
}

std::string bounds_text(const geometry::Box3& b) {
  return "X " + format_gcode_number(b.lo.x) + " .. " + format_gcode_number(b.hi.x) + ", Y " +
         format_gcode_number(b.lo.y) + " .. " + format_gcode_number(b.hi.y) + ", Z " + format_gcode_number(b.lo.z) +
         " .. " + format_gcode_number(b.hi.z);
}

}  // namespace

void register_stream(CLI::App& app, CommandRegistry& registry) {
  struct Opts {
    std::string file, output;
    ToolpathOptions tp;
    ConnectionOptions conn;
    SimCliOptions sim;
    ProgressMode progress = ProgressMode::Auto;
  };
  auto o = std::make_shared<Opts>();
  auto* sub = app.add_subcommand(
      "stream",
      "Stream a G-code file, or machine an STL (finishing path, plan, confirm), to a controller or `sim`. "
      "The bare form `cncstream FILE PORT ...` is the same command");
  sub->add_option("file", o->file, "G-code file (.nc .gcode .ngc .tap) or part (.stl)")->required()->check(CLI::ExistingFile);
  sub->add_option("port", o->conn.port, "Serial port, 'auto' (the one known controller board) or 'sim'")
      ->capture_default_str();
  add_connection_options(sub, o->conn);
  add_sim_options(sub, o->sim);
  add_toolpath_options(sub, o->tp, /*tool_required=*/false);
  for (auto* opt : sub->get_options())
    if (opt->get_group() == "Options" && opt->get_name().rfind("--", 0) == 0 &&
        std::string("--units --scale --tool --stepover --step --direction --strategy --steep-angle --scallop --feed --plunge-feed --rpm --safe-z "
                    "--tolerance --arcs --controller-arc-tolerance --bounds --floor --origin --z-zero --threads ")
                .find(opt->get_name() + " ") != std::string::npos)
      opt->group("Tool path (STL input)");
  sub->add_option("-o,--output", o->output, "STL input: write the generated G-code here (default: next to the journal)")
      ->group("Tool path (STL input)");
  add_progress_option(sub, o->progress);
  sub->get_option("--progress")->group("Tool path (STL input)");
  registry.add(sub, [o] {
    o->conn.link_rate = o->tp.link_rate;  // --link-rate: the program's link is the ETA's too
    const auto& c = o->conn;
    // Library tools become specs and --material sets the feeds, before a
    // daemon is handed the job (its library is not this one). The
    // simulator's rates are known; a real controller's come from its $$
    // only once connected: then --max-feed.
    std::optional<jobs::FeedsRequest> feeds_request;
    if (is_stl(o->file)) {
      tooling::MachineLimits machine;
      if (c.port == "sim") {
        const auto sim_limits = planning_limits(c, o->sim);
        machine.max_feed_xy = std::min(sim_limits.max_rate.x, sim_limits.max_rate.y);
        machine.max_feed_z = sim_limits.max_rate.z;
      }
      feeds_request = resolve_tool_options(o->tp, machine);
    }
    // A running daemon owns the port: it runs the job, this command follows it.
    if (const auto daemon = daemon_owning_port(c.port)) {
      HandoffJob h;
      h.file = o->file;
      h.stl = is_stl(o->file);
      if (h.stl && o->tp.tool.empty())
        throw std::invalid_argument(o->file + " is a part: say which cutter machines it with --tool (e.g. ball:3.175)");
      h.tp = o->tp;
      h.output = o->output;
      return hand_off_to_daemon(*daemon, h, c);
    }
    session::JobInput job;
    std::optional<VerifyTarget> verify;
    const auto limits = planning_limits(c, o->sim);
    const std::string limits_note = c.port == "sim" ? "the simulator's $110-$122"
                                                    : "GRBL default rates; refined from the controller's $$";
    if (is_stl(o->file)) {
      if (o->tp.tool.empty())
        throw std::invalid_argument(o->file + " is a part: say which cutter machines it with --tool (e.g. ball:3.175)");
      o->tp.part.stl = o->file;
      // Generation runs under its own Ctrl-C handling (stop the job, write
      // nothing, exit 130); the guard is gone before streaming, whose Ctrl-C
      // holds and stops the machine instead.
      std::optional<jobs::ToolpathProgram> program;
      jobs::FeedsPlan feeds;
      std::filesystem::path out;
      {
        LongJob generation(o->progress, o->tp.threads);
        std::string not_written = "no program written, nothing streamed";
        if (!o->output.empty()) not_written = o->output + " not written, nothing streamed";
        try {
          jobs::ToolpathParams params = toolpath_params(o->tp);
          // The built-in simulator powers on with G54 and G92 at zero (unless a settings file says otherwise).
          if (c.port == "sim" && o->sim.settings.empty() && params.stock && !params.stock->work_origin)
            params.stock->work_origin = geometry::Vec3{};
          feeds = apply_feeds(params, feeds_request);
          params.link = planning_link(c, o->sim);  // the machine's own link (the simulator's, a profile's, --serial)
          program = jobs::generate_toolpath(params, generation.control());
        } catch (const jobs::Cancelled&) {
          return generation.interrupted_exit(not_written);
        }
        generation.clear_progress();
        const std::string sha = transport::sha256_hex(program->gcode);
        out = o->output.empty() ? program_path(c, o->file, sha) : std::filesystem::path(o->output);
        jobs::write_text_file_atomically(out, program->gcode);
        // A stop that came after the job's last checkpoint: the program is
        // whole, but the operator asked not to go on.
        if (generation.interrupted())
          return generation.interrupted_exit(std::string("wrote ").append(out.string()).append(", nothing streamed"));
      }
      const jobs::ToolpathProgram& r = *program;
      job = session::job_from_file(out);
      EtaEstimator eta = estimate_job(job, limits, planning_link(c, o->sim));
      std::cout << "plan for " << o->file << ":\n";
      if (r.stock)
        std::cout << "  stock in work coordinates: " << bounds_text(*r.stock) << "\n";
      std::cout << operations_text(r, &eta) << jobs::feeds_plan_text(feeds, r)
                << "  tool tip in work coordinates: " << bounds_text(r.stats.work_bounds) << "\n"
                << "  work origin: XY at the part's " << o->tp.origin << ", Z0 at the part's " << o->tp.z_zero
                << " (set G54 there before cutting)\n"
                << "  program: " << out.string() << ", " << job.total_lines << " lines\n"
                << "  estimated machining time: " << format_duration(eta.total()) << " (" << limits_note << ")\n"
                << std::flush;
      if (!confirm("Start machining on " + c.port + "?", c.yes)) return 2;
      verify = VerifyTarget{r.work_mesh, r.cutter, {}, r.stock, r.work_offset};
      // The simulator cuts each operation with its own cutter.
      if (r.operations.size() > 1)
        for (const auto& op : r.operations) verify->tools[op.tool] = op.cutter;
      return run_session(c, o->sim, job, verify, std::move(eta));
    }
    job = session::job_from_file(o->file);
    EtaEstimator eta = estimate_job(job, limits, planning_link(c, o->sim));
    std::cout << o->file << ": " << job.total_lines << " lines, estimated machining time "
              << format_duration(eta.total()) << " (" << limits_note << ")" << std::endl;
    return run_session(c, o->sim, job, std::nullopt, std::move(eta));
  });
}

}  // namespace cncstream::app
