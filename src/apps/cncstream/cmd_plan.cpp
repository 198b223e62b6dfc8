// `cncstream plan PART.stl --tools ball:D,bull:D:r --stepover S --scallop-tol T -o plan/`:
// the thesis's recommendation made real. Machine the part with the cutter
// that removes more material, then clean up with the other only where the
// residual scallop exceeds the tolerance. One G-code file per tool (GRBL has
// no M6: the operator changes the tool between files), and the predicted
// machining time and largest residual of ball only, radiused only, combined.
#include <nlohmann/json.hpp>

#include <cmath>
#include <limits>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>

#include "cncstream/cam/cleanup.hpp"
#include "cncstream/cam/path_machining.hpp"
#include "cncstream/gcode/finishing_program.hpp"
#include "cncstream/gcode/program.hpp"
#include "commands.hpp"
#include "job_display.hpp"
#include "selection_job.hpp"

namespace cncstream::app {

namespace fs = std::filesystem;

namespace {

struct Option {
  std::string name;
  double seconds = 0;
  double max_residual = 0;          // over the part, mm
  double share_above_tol = 0;       // of on-part simulation nodes
  double max_scallop = 0;           // residual less what the option's cutters cannot reach at all
  double scallop_share_above_tol = 0;
};

// reach: per node the lowest height the option's cutters can reach at all
// (NaN where not computed: all of the residual counts as scallop).
Option evaluate(const std::string& name, const std::vector<std::string>& programs, const std::vector<double>& machined,
                const std::vector<double>& reach, const DesignHeights& design, double tol,
                const gcode::MotionLimits& limits) {
  Option o;
  o.name = name;
  for (const auto& text : programs) o.seconds += gcode::estimate_program_time(gcode::trace_program(text), limits).total();
  std::size_t on = 0, above = 0, scallop_above = 0;
  for (std::size_t k = 0; k < machined.size(); ++k) {
    if (design.off_part[k]) continue;
    const double r = machined[k] - design.z[k];
    const double unreachable = k < reach.size() ? unreachable_part(machined[k], design.z[k], reach[k]) : 0.0;
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

}  // namespace

void register_plan(CLI::App& app, CommandRegistry& registry) {
  struct Opts {
    SelectionOptions sel;
    std::string out = "plan";
  };
  auto o = std::make_shared<Opts>();
  auto* sub = app.add_subcommand(
      "plan", "Combined-tool plan: the cutter removing more material, then the other only where scallops exceed --scallop-tol");
  add_selection_options(sub, o->sel);
  sub->add_option("--feed", o->sel.feed, "Cutting feed, mm/min")->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--plunge-feed", o->sel.plunge_feed, "Plunge feed, mm/min")->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--rpm", o->sel.rpm, "Spindle speed")->check(CLI::NonNegativeNumber)->capture_default_str();
  sub->add_option("--max-rate", o->sel.max_rate, "Machine's max rate per axis for the time estimate, mm/min ($110-$112)")
      ->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--accel", o->sel.accel, "Machine's acceleration per axis for the time estimate, mm/s^2 ($120-$122)")
      ->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("-o,--output", o->out, "Folder for the G-code files and plan.json")->capture_default_str();
  registry.add(sub, [o] {
    SelectionOptions so = o->sel;
    // The clean-up is placed from the simulated residual: sample it finely
    // along the passes too (no speed target here, unlike the report).
    if (so.sim_along <= 0) so.sim_along = std::min(so.stepover, std::max(so.step, 0.2));
    const SelectionResult r = run_selection(so);
    std::cout << r.table();
    const bool along_x = so.direction != "y";
    const bool radiused_first = 2 * r.choice.radiused_by_volume >= r.choice.on_part;
    const CutterRun& first = radiused_first ? r.radiused : r.ball;
    const CutterRun& second = radiused_first ? r.ball : r.radiused;

    // Clean-up: the second cutter's rows where the first leaves too much.
    const GridSpec& sg = r.design.grid;
    // Only where the second cutter does better: corners neither reaches are
    // not worth a pass.
    std::vector<double> worth(sg.size(), std::numeric_limits<double>::quiet_NaN());
    for (std::size_t k = 0; k < sg.size(); ++k) {
      const double a = first.scallops.residual[k], b = second.scallops.residual[k];
      if (std::isfinite(a) && std::isfinite(b) && b < a - 0.25 * so.scallop_tol) worth[k] = a;
    }
    const std::vector<Polyline> pieces = cleanup_pieces(second.path, sg, worth, so.scallop_tol, second.cutter.radius, along_x);
    MachiningParams mp;
    mp.feed = so.feed;
    mp.plunge_feed = so.plunge_feed;
    mp.rpm = so.rpm;
    double top = -HUGE_VAL;
    for (const auto* run : {&r.ball, &r.radiused})
      for (const auto& row : run->path.rows)
        for (const auto& p : row) top = std::max(top, p.z);
    mp.safe_z = top + r.work_offset.z + 5;
    // The simulated clean-up, with its retracts (a straight move between
    // pieces would cut where the program does not).
    std::vector<Polyline> sim_pieces;
    const double sim_safe = mp.safe_z - r.work_offset.z;
    for (const auto& pl : pieces) {
      Polyline s;
      s.push_back({pl.front().x, pl.front().y, sim_safe});
      s.insert(s.end(), pl.begin(), pl.end());
      s.push_back({pl.back().x, pl.back().y, sim_safe});
      sim_pieces.push_back(std::move(s));
    }
    const std::vector<double> combined = machine_path(sg, first.machined, sim_pieces, second.cutter, so.threads);

    auto header = [&](const Cutter& c, const std::string& what, int tool) {
      MachiningParams p = mp;
      p.tool = tool;
      p.header_comments = {"cncstream plan: " + what, "part: " + so.part.stl, "tool: " + c.description() + " [" + c.spec() + "]",
                           "work origin: XY at the part's min, Z0 at the part's top"};
      return p;
    };
    const std::string prog_first = finishing_program(first.path, r.work_offset, header(first.cutter, "1 of 2, finishing", 1));
    const std::string prog_second =
        pieces.empty() ? std::string() : pieces_program(pieces, r.work_offset, header(second.cutter, "2 of 2, clean-up", 2));
    const std::string prog_ball = first.cutter.type == CutterType::Ball ? prog_first : finishing_program(r.ball.path, r.work_offset, mp);
    const std::string prog_rad =
        first.cutter.type == CutterType::Bull ? prog_first : finishing_program(r.radiused.path, r.work_offset, mp);

    gcode::MotionLimits limits;
    limits.max_rate = {so.max_rate, so.max_rate, so.max_rate};
    limits.acceleration = {so.accel, so.accel, so.accel};
    // What either cutter can reach; where one was not computed (it left
    // almost nothing there) the whole residual counts as scallop.
    std::vector<double> reach_either(sg.size(), std::numeric_limits<double>::quiet_NaN());
    if (r.ball.reach.size() == sg.size() && r.radiused.reach.size() == sg.size())
      for (std::size_t k = 0; k < sg.size(); ++k)
        if (std::isfinite(r.ball.reach[k]) && std::isfinite(r.radiused.reach[k]))
          reach_either[k] = std::min(r.ball.reach[k], r.radiused.reach[k]);
    std::vector<Option> options = {
        evaluate("ball only (" + r.ball.cutter.spec() + ")", {prog_ball}, r.ball.machined, r.ball.reach, r.design,
                 so.scallop_tol, limits),
        evaluate("radiused only (" + r.radiused.cutter.spec() + ")", {prog_rad}, r.radiused.machined, r.radiused.reach,
                 r.design, so.scallop_tol, limits),
        evaluate("combined (" + first.cutter.spec() + " then " + second.cutter.spec() + " clean-up)", {prog_first, prog_second},
                 combined, reach_either, r.design, so.scallop_tol, limits)};

    std::error_code ec;
    fs::create_directories(o->out, ec);
    if (ec) throw std::runtime_error("cannot create " + o->out + ": " + ec.message());
    auto safe = [](std::string s) {
      for (char& c : s)
        if (c == ':' || c == '/') c = '_';
      return s;
    };
    const std::string stem = fs::path(so.part.stl).stem().string();
    const fs::path f1 = fs::path(o->out) / (stem + "-1-" + safe(first.cutter.spec()) + ".nc");
    const fs::path f2 = fs::path(o->out) / (stem + "-2-" + safe(second.cutter.spec()) + ".nc");
    auto write = [](const fs::path& p, const std::string& text) {
      std::ofstream f(p);
      f << text;
      if (!f) throw std::runtime_error("cannot write " + p.string());
    };
    write(f1, prog_first);
    if (!pieces.empty()) write(f2, prog_second);

    std::cout << "plan (scallop tolerance " << so.scallop_tol << " mm; times at " << so.max_rate << " mm/min, " << so.accel
              << " mm/s^2 per axis):\n";
    std::cout << "  option                                              time      largest residual   nodes above tol"
                 "   largest scallop   scallop above tol\n";
    for (const auto& op : options)
      std::cout << "  " << std::left << std::setw(50) << op.name << std::right << std::setw(9) << format_duration(op.seconds) << "   "
                << std::fixed << std::setprecision(4) << std::setw(10) << op.max_residual << " mm   " << std::setprecision(2)
                << std::setw(10) << 100 * op.share_above_tol << " %" << std::setprecision(4) << std::setw(14)
                << op.max_scallop << " mm" << std::setprecision(2) << std::setw(17) << 100 * op.scallop_share_above_tol
                << " %\n";
    std::cout << "  (residual: all material left; scallop: less what no stepover of these cutters removes, such as gaps "
                 "narrower than the cutter)\n";
    std::cout << std::defaultfloat;
    std::cout << "wrote " << f1.string() << " (" << first.cutter.description() << ")\n";
    if (!pieces.empty())
      std::cout << "wrote " << f2.string() << " (" << second.cutter.description() << ", " << pieces.size()
                << " clean-up pieces)\n"
                << "GRBL has no tool changer command: run file 1, then change to the " << second.cutter.description()
                << ", set its Z zero on the part's top again (the tool length differs), and run file 2.\n";
    else
      std::cout << "no clean-up needed: the " << first.cutter.description() << " leaves nothing above the tolerance\n";

    nlohmann::json j;
    j["first"] = first.cutter.spec();
    j["second"] = second.cutter.spec();
    j["files"] = {f1.string()};
    if (!pieces.empty()) j["files"].push_back(f2.string());
    j["cleanup_pieces"] = pieces.size();
    j["scallop_tol_mm"] = so.scallop_tol;
    for (const auto& op : options)
      j["options"].push_back({{"name", op.name},
                              {"seconds", op.seconds},
                              {"max_residual_mm", op.max_residual},
                              {"share_above_tol", op.share_above_tol},
                              {"max_scallop_mm", op.max_scallop},
                              {"scallop_share_above_tol", op.scallop_share_above_tol}});
    write(fs::path(o->out) / "plan.json", j.dump(2) + "\n");
    return 0;
  });
}

}  // namespace cncstream::app
