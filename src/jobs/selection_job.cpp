#include "cncstream/jobs/selection_job.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/path_machining.hpp"
#include "cncstream/cam/reach.hpp"
#include "cncstream/cam/thread_limit.hpp"
#include "cncstream/jobs/work_setup.hpp"
#include "fixed_text.hpp"
#include "job_run.hpp"
#include "job_text.hpp"

namespace cncstream::jobs {

namespace {

// Scallop of the 2-D estimate as a function of the cross slope, tabulated.
std::vector<double> scallop_table(const cam::Cutter& c, double s) {
  std::vector<double> t(181);
  for (std::size_t k = 0; k < t.size(); ++k) t[k] = cam::scallop_2d(c, s, double(k) * 0.5 * M_PI / 180);
  return t;
}

// Residual up to which the reach split is not computed: it counts as scallop
// (an unreachable part this small is not reported anyway).
constexpr double kReachSplitMin = cam::kUnreachableMin;

}  // namespace

SelectionResult run_selection(const SelectionParams& o, const JobControl& control) {
  SelectionResult r;
  JobRun run(control);
  cam::run_with_thread_limit(control.threads, [&] {
    // Stage shares of the whole job as measured on the plaque (cut
    // simulation about half, CL grids and paths a third).
    const auto t_all = std::chrono::steady_clock::now();
    r.params = o;
    r.pair = o.cutters;
    run.stage("load", 0, 0.01);
    auto t0 = std::chrono::steady_clock::now();
    const std::shared_ptr<const geometry::Mesh> part = load_part(o.part);
    const geometry::Mesh& mesh = *part;
    r.facets = mesh.triangles.size();
    const geometry::Box3 box = mesh.bounds();
    const WorkSetup work = work_setup(box);
    r.work_offset = work.offset;
    r.timings.push_back({"load", seconds_since(t0)});

    const bool along_x = o.direction != cam::RasterDirection::Y;
    const cam::XYBounds b = cam::default_bounds(mesh, r.pair.ball);
    // Both finishing rasters on the G-code's lattice, as `toolpath` makes them;
    // their CL grids (every CL point of every pass) are where the choice is made.
    run.stage("CL grids + raster paths", 0.01, 0.30);
    t0 = std::chrono::steady_clock::now();
    const cam::ClEngine e_ball(mesh, r.pair.ball), e_rad(mesh, r.pair.radiused);
    std::optional<cam::ClEngine> e_tap;
    if (o.tapered) e_tap.emplace(mesh, *o.tapered);
    cam::RasterOptions ro;
    ro.stepover = o.stepover;
    ro.step = o.step;
    ro.direction = o.direction;
    ro.lattice = work.lattice;
    ro.keep_grid = true;
    r.ball.cutter = r.pair.ball;
    r.radiused.cutter = r.pair.radiused;
    const double raster_share = e_tap ? 1.0 / 3 : 0.5;
    r.ball.path = cam::build_raster(e_ball, b, ro, [&](double f) { run.within(raster_share * f); });
    r.radiused.path = cam::build_raster(e_rad, b, ro, [&](double f) { run.within(raster_share * (1 + f)); });
    if (e_tap) {
      r.tapered.emplace();
      r.tapered->cutter = *o.tapered;
      r.tapered->path = cam::build_raster(*e_tap, b, ro, [&](double f) { run.within(raster_share * (2 + f)); });
    }
    r.timings.push_back({"CL grids + raster paths", seconds_since(t0)});
    run.stage("choice", 0.30, 0.33);
    t0 = std::chrono::steady_clock::now();
    const cam::ClGrid& g_ball = r.ball.path.grid;
    const cam::GridSpec& ag = g_ball.spec;
    r.choice = cam::choose_by_removal(r.pair, g_ball, r.radiused.path.grid);
    r.profile = cam::slope_profile(r.choice, 5);
    r.timings.push_back({"choice", seconds_since(t0)});

    // The cut simulation grid over the part: fine across the passes.
    run.stage("design heights", 0.33, 0.35);
    t0 = std::chrono::steady_clock::now();
    // Across, 8 nodes per stepover starting on the first pass, so the nodes
    // fall on every pass and on the cusps between them (on level ground);
    // along, one column per stepover: a scallop changes along a pass only as
    // the surface does, so this samples the pass pairs on a square pattern.
    const double along = o.sim_along > 0 ? o.sim_along : std::max(o.step, r.ball.path.stepover);
    const double fine = r.ball.path.stepover / 8;
    const double first = along_x ? r.ball.path.rows.front().front().y : r.ball.path.rows.front().front().x;
    const double lo_across = along_x ? box.lo.y : box.lo.x;
    const double start = first - std::ceil((first - lo_across) / fine - 1e-9) * fine;
    const cam::GridSpec sg = along_x ? cam::GridSpec::covering(box.lo.x, start, box.hi.x, box.hi.y, along, fine)
                                : cam::GridSpec::covering(start, box.lo.y, box.hi.x, box.hi.y, fine, along);
    r.design = cam::design_heights(mesh, sg);
    r.timings.push_back({"design heights", seconds_since(t0)});
    run.stage("cut simulation", 0.35, 0.85);
    t0 = std::chrono::steady_clock::now();
    const double stock_top = box.hi.z + 1;
    const std::vector<CutterRun*> runs = r.runs();
    const double share = 1.0 / double(runs.size());
    for (std::size_t n = 0; n < runs.size(); ++n) {
      CutterRun* cr = runs[n];
      const double base = double(n) * share;
      cr->machined = cam::machine_path(sg, std::vector<double>(sg.size(), stock_top), cam::raster_pieces(cr->path), cr->cutter,
                                  [&](double f) { run.within(base + share * f); });
    }
    r.timings.push_back({"cut simulation", seconds_since(t0)});

    // Reach limits: what each cutter leaves with its tip on every node of a
    // dense CL lattice. Residual above that is material no stepover removes
    // (gaps narrower than the cutter), not scallop. Nodes with almost nothing
    // left need no split.
    run.stage("reach limits", 0.85, 0.99);
    t0 = std::chrono::steady_clock::now();
    // Default: stepover/3, which on the simulation grid's alignment gives
    // stepover/3 along the passes and stepover/4 across (0.133 x 0.1 mm at 0.4).
    const double pitch = o.reach_pitch < 0 ? std::min(0.15, o.stepover / 3) : o.reach_pitch;
    for (std::size_t n = 0; n < runs.size(); ++n) {
      CutterRun* cr = runs[n];
      const double base = double(n) * share;
      std::vector<double> rows;
      for (const auto& row : cr->path.rows) rows.push_back(along_x ? row.front().y : row.front().x);
      std::vector<double> reach;
      if (pitch > 0) {
        const cam::ClEngine& e = cr == &r.ball ? e_ball : cr == &r.radiused ? e_rad : *e_tap;
        std::vector<std::uint8_t> wanted(sg.size(), 0);
        for (std::size_t k = 0; k < sg.size(); ++k)
          wanted[k] = !r.design.off_part[k] && cr->machined[k] - r.design.z[k] > kReachSplitMin;
        const cam::ClGrid dense = e.compute(cam::reach_lattice(sg, b.x0, b.y0, b.x1, b.y1, pitch, pitch),
                                       [&](double f) { run.within(base + 0.5 * share * f); });
        reach = cam::reach_heights(dense, cr->cutter, sg, wanted,
                              [&](double f) { run.within(base + 0.5 * share * (1 + f)); });
      }
      cr->scallops = cam::scallops_from_cut(sg, cr->machined, r.design, rows, along_x, pitch > 0 ? &reach : nullptr);
      cr->reach = std::move(reach);
    }
    if (pitch > 0) r.timings.push_back({"reach limits", seconds_since(t0)});

    // The 2-D estimate at every analysis node from the slope across the passes.
    run.stage("scallops", 0.99, 1.0);
    for (CutterRun* cr : runs) {
      const auto table = scallop_table(cr->cutter, o.stepover);
      std::vector<double> est(ag.size(), std::numeric_limits<double>::quiet_NaN());
      const cam::ClGrid& g = g_ball;
      for (std::size_t j = 1; j + 1 < ag.ny; ++j)
        for (std::size_t i = 1; i + 1 < ag.nx; ++i) {
          const std::size_t k = j * ag.nx + i;
          if (!std::isfinite(r.choice.d[k])) continue;
          const double grad = along_x ? (g.at(i, j + 1) - g.at(i, j - 1)) / (2 * ag.dy)
                                      : (g.at(i + 1, j) - g.at(i - 1, j)) / (2 * ag.dx);
          const double deg = std::atan(std::fabs(grad)) * 180 / M_PI;
          const double f = std::min(deg / 0.5, 179.999);
          const auto lo = static_cast<std::size_t>(f);
          est[k] = table[lo] + (table[lo + 1] - table[lo]) * (f - double(lo));
        }
      cr->estimate_2d = cam::scallop_stats(est);
    }

    // The cutter leaving the smaller scallop, per pass pair and column.
    r.min_scallop_choice.assign(sg.size(), static_cast<std::int8_t>(cam::Choice::None));
    for (std::size_t k = 0; k < sg.size(); ++k) {
      const double a = r.ball.scallops.strip[k], c = r.radiused.scallops.strip[k];
      if (!std::isfinite(a) || !std::isfinite(c)) continue;
      r.min_scallop_choice[k] =
          std::fabs(a - c) <= 1e-3 ? std::int8_t{2} : static_cast<std::int8_t>(a < c ? cam::Choice::Ball : cam::Choice::Radiused);
    }
    r.seconds = seconds_since(t_all);
  });
  run.finish();
  return r;
}

std::vector<const CutterRun*> SelectionResult::runs() const {
  std::vector<const CutterRun*> v{&ball, &radiused};
  if (tapered) v.push_back(&*tapered);
  return v;
}

std::vector<CutterRun*> SelectionResult::runs() {
  std::vector<CutterRun*> v{&ball, &radiused};
  if (tapered) v.push_back(&*tapered);
  return v;
}

std::string SelectionResult::table() const {
  const auto mm = [](double v, int digits = 4) { return fixed_text(v, digits); };
  std::ostringstream o;
  const double vol_sw = cam::switch_angle(pair.rc(), choice.d_base_volume) * 180 / M_PI;
  const double area_sw = cam::switch_angle(pair.rc(), choice.d_base_area) * 180 / M_PI;
  o << "cutters: " << pair.ball.description() << " [" << pair.ball.spec() << "] vs " << pair.radiused.description() << " ["
    << pair.radiused.spec() << "]";
  if (tapered) o << ", beside them " << tapered->cutter.description() << " [" << tapered->cutter.spec() << "]";
  o << "\n";
  o << "d_base: volume " << mm(choice.d_base_volume) << " mm, area " << mm(choice.d_base_area) << " mm (corrected forms)\n";
  const double on = std::max<double>(1, double(choice.on_part));
  o << "radiused removes more on " << mm(100 * double(choice.radiused_by_volume) / on, 1) << " % of the part by volume, "
    << mm(100 * double(choice.radiused_by_area) / on, 1) << " % by area (ball: the rest)\n";
  o << "switch slope: volume " << mm(vol_sw, 1) << " deg (plane), " << mm(profile.switch_deg_volume, 1)
    << " deg measured on the part; area " << mm(area_sw, 1) << " deg (plane), " << mm(profile.switch_deg_area, 1)
    << " deg measured\n";
  o << "scallop heights, stepover " << mm(params.stepover, 3) << " mm (Table 4.1 form):\n";
  o << "  cutter                   method            max mm    min mm    mean mm\n";
  for (const CutterRun* run : runs()) {
    auto row = [&](const char* method, const cam::ScallopStats& s) {
      o << "  " << std::left << std::setw(24) << run->cutter.spec() << " " << std::setw(16) << method << std::right
        << std::setw(8) << mm(s.max) << "  " << std::setw(8) << mm(s.min) << "  " << std::setw(8) << mm(s.mean) << "\n";
    };
    row("cut simulation", run->scallops.stats);
    row("2-D estimate", run->estimate_2d);
  }
  if (ball.scallops.unreachable_stats.computed) {
    o << "material no stepover removes (gaps and inside corners narrower than the cutter; not counted as scallop):\n";
    for (const CutterRun* run : runs()) {
      const cam::UnreachableStats& u = run->scallops.unreachable_stats;
      o << "  " << std::left << std::setw(24) << run->cutter.spec() << std::right << " max " << mm(u.max) << " mm at ("
        << mm(u.max_x + work_offset.x, 2) << ", " << mm(u.max_y + work_offset.y, 2) << ") work, mean " << mm(u.mean)
        << " mm, more than " << mm(cam::kUnreachableMin, 2) << " mm on " << mm(100 * u.share, 1) << " % of the part\n";
    }
  }
  o << "time: " << mm(seconds, 2) << " s (";
  for (std::size_t k = 0; k < timings.size(); ++k) o << (k ? ", " : "") << timings[k].first << " " << mm(timings[k].second, 2);
  o << ")\n";
  return o.str();
}

}  // namespace cncstream::jobs
