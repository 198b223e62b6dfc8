#include "cncstream/jobs/plan_job.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "cncstream/cam/cleanup.hpp"
#include "cncstream/cam/path_machining.hpp"
#include "cncstream/cam/thread_limit.hpp"
#include "cncstream/gcode/finishing_program.hpp"
#include "cncstream/gcode/job_program.hpp"
#include "cncstream/gcode/program.hpp"
#include "cncstream/jobs/output_file.hpp"
#include "job_run.hpp"
#include "job_text.hpp"

namespace cncstream::jobs {

namespace fs = std::filesystem;

namespace {

// reach: per node the lowest height the option's cutters can reach at all
// (NaN where not computed: all of the residual counts as scallop).
PlanOption evaluate(const std::string& name, const std::vector<const std::string*>& programs,
                    const std::vector<double>& machined, const std::vector<double>& reach, const cam::DesignHeights& design,
                    double tol, const gcode::MotionLimits& limits, JobRun& run) {
  PlanOption o;
  o.name = name;
  for (const std::string* text : programs) {
    run.check();
    o.seconds += gcode::estimate_program_time(gcode::trace_program(*text), limits).total();
  }
  std::size_t on = 0, above = 0, scallop_above = 0;
  for (std::size_t k = 0; k < machined.size(); ++k) {
    if (design.off_part[k]) continue;
    const double r = machined[k] - design.z[k];
    const double unreachable = k < reach.size() ? cam::unreachable_part(machined[k], design.z[k], reach[k]) : 0.0;
    o.max_residual = std::max(o.max_residual, r);
    o.max_scallop = std::max(o.max_scallop, r - unreachable);
    ++on;
    above += r > tol;
    scallop_above += r - unreachable > tol;
  }
  o.share_above_tol = on ? double(above) / double(on) : 0;
  o.scallop_share_above_tol = on ? double(scallop_above) / double(on) : 0;
  return o;
}

// Share of the whole plan job taken by the selection (measured on the plaque).
constexpr double kSelectionShare = 0.75;

}  // namespace

PlanResult run_plan(const PlanParams& params, const JobControl& control) {
  PlanResult p;
  p.params = params;
  SelectionParams& so = p.params.selection;
  // The clean-up is placed from the simulated residual: sample it finely
  // along the passes too (no speed target here, unlike the report).
  if (so.sim_along <= 0) so.sim_along = std::min(so.stepover, std::max(so.step, 0.2));
  JobRun run(control);
  cam::run_with_thread_limit(control.threads, [&] {
    p.selection = run_selection(so, run.nested(0, kSelectionShare));
    const SelectionResult& r = p.selection;
    const bool along_x = so.direction != cam::RasterDirection::Y;
    p.radiused_first = 2 * r.choice.radiused_by_volume >= r.choice.on_part;
    const CutterRun& first = p.first();
    const CutterRun& second = p.second();

    // Clean-up: the second cutter's rows where the first leaves too much.
    run.stage("clean-up", kSelectionShare, 0.85);
    const cam::GridSpec& sg = r.design.grid;
    // Only where the second cutter does better: corners neither reaches are
    // not worth a pass.
    std::vector<double> worth(sg.size(), std::numeric_limits<double>::quiet_NaN());
    for (std::size_t k = 0; k < sg.size(); ++k) {
      const double a = first.scallops.residual[k], b = second.scallops.residual[k];
      if (std::isfinite(a) && std::isfinite(b) && b < a - 0.25 * so.scallop_tol) worth[k] = a;
    }
    p.cleanup_pieces = cam::cleanup_pieces(second.path, sg, worth, so.scallop_tol, second.cutter.radius, along_x);
    const std::vector<cam::Polyline>& pieces = p.cleanup_pieces;
    MachiningParams mp;
    mp.feed = params.feed;
    mp.plunge_feed = params.plunge_feed;
    mp.rpm = params.rpm;
    double top = -HUGE_VAL;
    for (const auto* cr : {&r.ball, &r.radiused})
      for (const auto& row : cr->path.rows)
        for (const auto& pt : row) top = std::max(top, pt.z);
    mp.safe_z = top + r.work_offset.z + 5;
    // A cutter's own feeds and speed, where the plan has them (--material).
    auto rate_for = [&](const cam::Cutter& c) {
      const auto& rate = c.type == cam::CutterType::Ball ? params.ball_rate : params.radiused_rate;
      MachiningParams m = mp;
      if (rate) {
        m.feed = rate->feed;
        m.plunge_feed = rate->plunge_feed;
        m.rpm = rate->rpm;
      }
      return m;
    };
    // The simulated clean-up, with its retracts (a straight move between
    // pieces would cut where the program does not).
    std::vector<cam::Polyline> sim_pieces;
    const double sim_safe = mp.safe_z - r.work_offset.z;
    for (const auto& pl : pieces) {
      cam::Polyline s;
      s.push_back({pl.front().x, pl.front().y, sim_safe});
      s.insert(s.end(), pl.begin(), pl.end());
      s.push_back({pl.back().x, pl.back().y, sim_safe});
      sim_pieces.push_back(std::move(s));
    }
    const std::vector<double> combined = cam::machine_path(sg, first.machined, sim_pieces, second.cutter, run.checkpoint());

    run.stage("programs", 0.85, 0.88);
    auto header = [&](const cam::Cutter& c, const std::string& what, int tool) {
      MachiningParams h = rate_for(c);
      h.tool = tool;
      h.header_comments = {"cncstream plan: " + what, "part: " + so.part.stl,
                           "tool: " + c.description() + " [" + c.spec() + "]",
                           "work origin: XY at the part's min, Z0 at the part's top"};
      return h;
    };
    p.program_first = finishing_program(first.path, r.work_offset, header(first.cutter, "1 of 2, finishing", 1));
    p.program_second = pieces.empty() ? std::string()
                                      : pieces_program(pieces, r.work_offset, header(second.cutter, "2 of 2, clean-up", 2));
    {
      // Both operations in one program, the tool change between them.
      JobProgramOptions jo;
      jo.decimals = mp.decimals;
      jo.safe_z = mp.safe_z;
      jo.dwell_s = mp.dwell_s;
      jo.header_comments = {"cncstream plan: finishing with " + first.cutter.spec() +
                                (pieces.empty() ? std::string(" (no clean-up needed)")
                                                : ", then clean-up with " + second.cutter.spec()),
                            "part: " + so.part.stl, "work origin: XY at the part's min, Z0 at the part's top"};
      JobProgram job(jo);
      job.begin_operation({"finishing", 1, first.cutter, rate_for(first.cutter).rpm});
      write_pieces(job.writer(), raster_as_one_cut(first.path), r.work_offset, rate_for(first.cutter), job.stats());
      if (!pieces.empty()) {
        job.begin_operation({"clean-up", 2, second.cutter, rate_for(second.cutter).rpm});
        write_pieces(job.writer(), pieces, r.work_offset, rate_for(second.cutter), job.stats());
      }
      p.program_job = job.finish();
    }
    const std::string prog_ball =
        first.cutter.type == cam::CutterType::Ball ? p.program_first
                                              : finishing_program(r.ball.path, r.work_offset, rate_for(r.ball.cutter));
    const std::string prog_rad =
        first.cutter.type == cam::CutterType::Bull
            ? p.program_first
            : finishing_program(r.radiused.path, r.work_offset, rate_for(r.radiused.cutter));

    run.stage("estimates", 0.88, 1.0);
    gcode::MotionLimits limits;
    limits.max_rate = {params.max_rate, params.max_rate, params.max_rate};
    limits.acceleration = {params.accel, params.accel, params.accel};
    // What either cutter can reach; where one was not computed (it left
    // almost nothing there) the whole residual counts as scallop.
    std::vector<double> reach_either(sg.size(), std::numeric_limits<double>::quiet_NaN());
    if (r.ball.reach.size() == sg.size() && r.radiused.reach.size() == sg.size())
      for (std::size_t k = 0; k < sg.size(); ++k)
        if (std::isfinite(r.ball.reach[k]) && std::isfinite(r.radiused.reach[k]))
          reach_either[k] = std::min(r.ball.reach[k], r.radiused.reach[k]);
    p.options.push_back(evaluate("ball only (" + r.ball.cutter.spec() + ")", {&prog_ball}, r.ball.machined, r.ball.reach,
                                 r.design, so.scallop_tol, limits, run));
    run.within(1.0 / 3);
    p.options.push_back(evaluate("radiused only (" + r.radiused.cutter.spec() + ")", {&prog_rad}, r.radiused.machined,
                                 r.radiused.reach, r.design, so.scallop_tol, limits, run));
    run.within(2.0 / 3);
    p.options.push_back(evaluate("combined (" + first.cutter.spec() + " then " + second.cutter.spec() + " clean-up)",
                                 {&p.program_first, &p.program_second}, combined, reach_either, r.design,
                                 so.scallop_tol, limits, run));
  });
  run.finish();
  return p;
}

PlanFiles write_plan(const PlanResult& plan, const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error("cannot create " + dir.string() + ": " + ec.message());
  const CutterRun& first = plan.first();
  const CutterRun& second = plan.second();
  const bool cleanup = !plan.cleanup_pieces.empty();
  const auto write = write_text_file_atomically;  // its errors name the file and what failed
  // plan.json is written last: an earlier plan's must not vouch for files of a plan that fails half-way.
  fs::remove(dir / "plan.json", ec);
  PlanFiles files;
  const std::string stem = fs::path(plan.params.selection.part.stl).stem().string();
  files.first = dir / (stem + "-1-" + safe_name(first.cutter.spec()) + ".nc");
  write(files.first, plan.program_first);
  if (cleanup) {
    files.second = dir / (stem + "-2-" + safe_name(second.cutter.spec()) + ".nc");
    write(files.second, plan.program_second);
  }
  files.job = dir / (stem + "-job.nc");
  write(files.job, plan.program_job);

  nlohmann::json j;
  j["first"] = first.cutter.spec();
  j["second"] = second.cutter.spec();
  j["files"] = {files.first.string()};
  if (cleanup) j["files"].push_back(files.second.string());
  j["job_file"] = files.job.string();
  j["cleanup_pieces"] = plan.cleanup_pieces.size();
  j["scallop_tol_mm"] = plan.params.selection.scallop_tol;
  for (const auto& op : plan.options)
    j["options"].push_back({{"name", op.name},
                            {"seconds", op.seconds},
                            {"max_residual_mm", op.max_residual},
                            {"share_above_tol", op.share_above_tol},
                            {"max_scallop_mm", op.max_scallop},
                            {"scallop_share_above_tol", op.scallop_share_above_tol}});
  files.json = dir / "plan.json";
  write(files.json, j.dump(2) + "\n");
  return files;
}

}  // namespace cncstream::jobs
