#include "selection_job.hpp"

#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <exception>
#include <functional>
#include <mutex>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <thread>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/path_machining.hpp"
#include "cncstream/cam/reach.hpp"
#include "cncstream/gcode/finishing_program.hpp"
#include "cncstream/gcode/gcode_writer.hpp"
#include "cncstream/image/category_map.hpp"
#include "cncstream/image/height_map.hpp"

namespace cncstream::app {

namespace fs = std::filesystem;

void add_selection_options(CLI::App* sub, SelectionOptions& o) {
  sub->add_option("stl", o.part.stl, "STL file")->required();
  add_part_options(sub, o.part);
  sub->add_option("--tools", o.tools, "The ball and the radiused cutter, same diameter: ball:D,bull:D:r")->capture_default_str();
  sub->add_option("--stepover", o.stepover, "Distance between passes, mm")->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--step", o.step, "Sampling step along the passes, mm")->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--direction", o.direction, "Pass direction: x or y")->check(CLI::IsMember({"x", "y"}))->capture_default_str();
  sub->add_option("--scallop-tol", o.scallop_tol, "Scallop height accepted, mm (the plan cleans up above it)")
      ->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--reach-pitch", o.reach_pitch,
                  "CL lattice pitch for each cutter's reach limit, which splits material left into scallop and "
                  "unreachable (gaps narrower than the cutter), mm; 0: no split; default min(0.15, stepover/3)");
  sub->add_option("--threads", o.threads, "Worker threads (0: all cores)");
  sub->add_flag("--nodes-csv", o.nodes_csv,
                "Also write nodes.csv: every CL point of the passes with both tip heights, d, slope and both choices "
                "(about 60 bytes a node)");
}

namespace {

CutterPair parse_pair(const std::string& tools) {
  std::vector<Cutter> cs;
  std::stringstream ss(tools);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) cs.push_back(parse_cutter_spec(item));
  if (cs.size() != 2) throw std::invalid_argument("--tools '" + tools + "': give exactly two cutters, e.g. ball:3.175,bull:3.175:0.79");
  if (cs[0].type != CutterType::Ball) std::swap(cs[0], cs[1]);
  return CutterPair(cs[0], cs[1]);
}

// Scallop of the 2-D estimate as a function of the cross slope, tabulated.
std::vector<double> scallop_table(const Cutter& c, double s) {
  std::vector<double> t(181);
  for (std::size_t k = 0; k < t.size(); ++k) t[k] = scallop_2d(c, s, double(k) * 0.5 * M_PI / 180);
  return t;
}

// Residual up to which the reach split is not computed: it counts as scallop
// (an unreachable part this small is not reported anyway).
constexpr double kReachSplitMin = kUnreachableMin;

MapGrid map_grid(const GridSpec& g) { return {g.nx, g.ny, g.dx, g.dy, g.x0, g.y0}; }

std::string mm(double v, int digits = 4) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(digits) << v;
  return o.str();
}

}  // namespace

SelectionResult run_selection(const SelectionOptions& o) {
  const auto t_all = std::chrono::steady_clock::now();
  SelectionResult r;
  r.options = o;
  r.pair = parse_pair(o.tools);
  auto t0 = std::chrono::steady_clock::now();
  const StlLoadResult part = load_part(o.part);
  const Mesh& mesh = part.mesh;
  r.facets = mesh.triangles.size();
  const Box3 box = mesh.bounds();
  r.work_offset = work_offset(box, XYOrigin::PartMin, ZZero::PartTop);
  r.timings.push_back({"load", seconds_since(t0)});

  const bool along_x = o.direction != "y";
  const XYBounds b = default_bounds(mesh, r.pair.ball);
  ClOptions clo;
  clo.threads = o.threads;
  // Both finishing rasters on the G-code's lattice, as `toolpath` makes them;
  // their CL grids (every CL point of every pass) are where the choice is made.
  t0 = std::chrono::steady_clock::now();
  const ClEngine e_ball(mesh, r.pair.ball, clo), e_rad(mesh, r.pair.radiused, clo);
  RasterOptions ro;
  ro.stepover = o.stepover;
  ro.step = o.step;
  ro.direction = along_x ? RasterDirection::X : RasterDirection::Y;
  ro.lattice = XYLattice{0.001, -r.work_offset.x, -r.work_offset.y};
  ro.keep_grid = true;
  r.ball.cutter = r.pair.ball;
  r.radiused.cutter = r.pair.radiused;
  r.ball.path = build_raster(e_ball, b, ro);
  r.radiused.path = build_raster(e_rad, b, ro);
  r.timings.push_back({"CL grids + raster paths", seconds_since(t0)});
  t0 = std::chrono::steady_clock::now();
  const ClGrid& g_ball = r.ball.path.grid;
  const GridSpec& ag = g_ball.spec;
  r.choice = choose_by_removal(r.pair, g_ball, r.radiused.path.grid);
  r.profile = slope_profile(r.choice, 5);
  r.timings.push_back({"choice", seconds_since(t0)});

  // The cut simulation grid over the part: fine across the passes.
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
  const GridSpec sg = along_x ? GridSpec::covering(box.lo.x, start, box.hi.x, box.hi.y, along, fine)
                              : GridSpec::covering(start, box.lo.y, box.hi.x, box.hi.y, fine, along);
  r.design = design_heights(mesh, sg);
  r.timings.push_back({"design heights", seconds_since(t0)});
  t0 = std::chrono::steady_clock::now();
  const double stock_top = box.hi.z + 1;
  for (CutterRun* run : {&r.ball, &r.radiused})
    run->machined = machine_path(sg, std::vector<double>(sg.size(), stock_top), raster_pieces(run->path), run->cutter,
                                 o.threads);
  r.timings.push_back({"cut simulation", seconds_since(t0)});

  // Reach limits: what each cutter leaves with its tip on every node of a
  // dense CL lattice. Residual above that is material no stepover removes
  // (gaps narrower than the cutter), not scallop. Nodes with almost nothing
  // left need no split.
  t0 = std::chrono::steady_clock::now();
  // Default: stepover/3, which on the simulation grid's alignment gives
  // stepover/3 along the passes and stepover/4 across (0.133 x 0.1 mm at 0.4).
  const double pitch = o.reach_pitch < 0 ? std::min(0.15, o.stepover / 3) : o.reach_pitch;
  for (CutterRun* run : {&r.ball, &r.radiused}) {
    std::vector<double> rows;
    for (const auto& row : run->path.rows) rows.push_back(along_x ? row.front().y : row.front().x);
    std::vector<double> reach;
    if (pitch > 0) {
      const ClEngine& e = run == &r.ball ? e_ball : e_rad;
      std::vector<std::uint8_t> wanted(sg.size(), 0);
      for (std::size_t k = 0; k < sg.size(); ++k)
        wanted[k] = !r.design.off_part[k] && run->machined[k] - r.design.z[k] > kReachSplitMin;
      const ClGrid dense = e.compute(reach_lattice(sg, b.x0, b.y0, b.x1, b.y1, pitch, pitch));
      reach = reach_heights(dense, run->cutter, sg, wanted, o.threads);
    }
    run->scallops = scallops_from_cut(sg, run->machined, r.design, rows, along_x, pitch > 0 ? &reach : nullptr);
    run->reach = std::move(reach);
  }
  if (pitch > 0) r.timings.push_back({"reach limits", seconds_since(t0)});

  // The 2-D estimate at every analysis node from the slope across the passes.
  for (CutterRun* run : {&r.ball, &r.radiused}) {
    const auto table = scallop_table(run->cutter, o.stepover);
    std::vector<double> est(ag.size(), std::numeric_limits<double>::quiet_NaN());
    const ClGrid& g = g_ball;
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
    run->estimate_2d = scallop_stats(est);
  }

  // The cutter leaving the smaller scallop, per pass pair and column.
  r.min_scallop_choice.assign(sg.size(), static_cast<std::int8_t>(Choice::None));
  for (std::size_t k = 0; k < sg.size(); ++k) {
    const double a = r.ball.scallops.strip[k], c = r.radiused.scallops.strip[k];
    if (!std::isfinite(a) || !std::isfinite(c)) continue;
    r.min_scallop_choice[k] = std::fabs(a - c) <= 1e-3 ? 2 : static_cast<std::int8_t>(a < c ? Choice::Ball : Choice::Radiused);
  }
  r.seconds = seconds_since(t_all);
  return r;
}

std::string SelectionResult::table() const {
  std::ostringstream o;
  const double vol_sw = switch_angle(pair.rc(), choice.d_base_volume) * 180 / M_PI;
  const double area_sw = switch_angle(pair.rc(), choice.d_base_area) * 180 / M_PI;
  o << "cutters: " << pair.ball.description() << " [" << pair.ball.spec() << "] vs " << pair.radiused.description() << " ["
    << pair.radiused.spec() << "]\n";
  o << "d_base: volume " << mm(choice.d_base_volume) << " mm, area " << mm(choice.d_base_area) << " mm (corrected forms)\n";
  const double on = std::max<double>(1, double(choice.on_part));
  o << "radiused removes more on " << mm(100 * double(choice.radiused_by_volume) / on, 1) << " % of the part by volume, "
    << mm(100 * double(choice.radiused_by_area) / on, 1) << " % by area (ball: the rest)\n";
  o << "switch slope: volume " << mm(vol_sw, 1) << " deg (plane), " << mm(profile.switch_deg_volume, 1)
    << " deg measured on the part; area " << mm(area_sw, 1) << " deg (plane), " << mm(profile.switch_deg_area, 1)
    << " deg measured\n";
  o << "scallop heights, stepover " << mm(options.stepover, 3) << " mm (Table 4.1 form):\n";
  o << "  cutter                   method            max mm    min mm    mean mm\n";
  for (const CutterRun* run : {&ball, &radiused}) {
    auto row = [&](const char* method, const ScallopStats& s) {
      o << "  " << std::left << std::setw(24) << run->cutter.spec() << " " << std::setw(16) << method << std::right
        << std::setw(8) << mm(s.max) << "  " << std::setw(8) << mm(s.min) << "  " << std::setw(8) << mm(s.mean) << "\n";
    };
    row("cut simulation", run->scallops.stats);
    row("2-D estimate", run->estimate_2d);
  }
  if (ball.scallops.unreachable_stats.computed) {
    o << "material no stepover removes (gaps and inside corners narrower than the cutter; not counted as scallop):\n";
    for (const CutterRun* run : {&ball, &radiused}) {
      const UnreachableStats& u = run->scallops.unreachable_stats;
      o << "  " << std::left << std::setw(24) << run->cutter.spec() << std::right << " max " << mm(u.max) << " mm at ("
        << mm(u.max_x + work_offset.x, 2) << ", " << mm(u.max_y + work_offset.y, 2) << ") work, mean " << mm(u.mean)
        << " mm, more than " << mm(kUnreachableMin, 2) << " mm on " << mm(100 * u.share, 1) << " % of the part\n";
    }
  }
  o << "time: " << mm(seconds, 2) << " s (";
  for (std::size_t k = 0; k < timings.size(); ++k) o << (k ? ", " : "") << timings[k].first << " " << mm(timings[k].second, 2);
  o << ")\n";
  return o.str();
}

std::vector<fs::path> write_selection_report(const SelectionResult& r, const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error("cannot create report folder " + dir.string() + ": " + ec.message());
  std::vector<fs::path> files;
  const std::string ball = r.pair.ball.spec(), rad = r.pair.radiused.spec();
  auto safe = [](std::string s) {
    for (char& c : s)
      if (c == ':' || c == '/') c = '_';
    return s;
  };

  // Numbers: JSON and CSV.
  nlohmann::json j;
  j["part"] = r.options.part.stl;
  j["facets"] = r.facets;
  j["stepover_mm"] = r.options.stepover;
  j["step_mm"] = r.options.step;
  j["direction"] = r.options.direction;
  j["cutters"] = {{"ball", ball}, {"radiused", rad}};
  j["d_base_mm"] = {{"volume", r.choice.d_base_volume}, {"area", r.choice.d_base_area}};
  j["switch_deg"] = {{"volume_plane", switch_angle(r.pair.rc(), r.choice.d_base_volume) * 180 / M_PI},
                     {"area_plane", switch_angle(r.pair.rc(), r.choice.d_base_area) * 180 / M_PI},
                     {"volume_measured", std::isfinite(r.profile.switch_deg_volume) ? nlohmann::json(r.profile.switch_deg_volume) : nlohmann::json()},
                     {"area_measured", std::isfinite(r.profile.switch_deg_area) ? nlohmann::json(r.profile.switch_deg_area) : nlohmann::json()}};
  const double on = std::max<double>(1, double(r.choice.on_part));
  j["share_radiused_pct"] = {{"volume", 100 * double(r.choice.radiused_by_volume) / on},
                             {"area", 100 * double(r.choice.radiused_by_area) / on}};
  j["analysis_nodes_on_part"] = r.choice.on_part;
  auto stats = [](const ScallopStats& s) {
    return nlohmann::json{{"max_mm", s.max}, {"min_mm", s.min}, {"mean_mm", s.mean}, {"samples", s.samples}};
  };
  for (const CutterRun* run : {&r.ball, &r.radiused}) {
    j["scallop"][run->cutter.spec()] = {{"cut_simulation", stats(run->scallops.stats)},
                                        {"estimate_2d", stats(run->estimate_2d)}};
    const UnreachableStats& u = run->scallops.unreachable_stats;
    if (u.computed)
      j["unreachable"][run->cutter.spec()] = {{"max_mm", u.max},
                                              {"at_work_xy", {u.max_x + r.work_offset.x, u.max_y + r.work_offset.y}},
                                              {"mean_mm", u.mean},
                                              {"share_above_min_pct", 100 * u.share},
                                              {"min_mm", kUnreachableMin}};
  }
  for (const auto& bin : r.profile.bins)
    if (bin.nodes)
      j["slope_bins"].push_back({{"lo_deg", bin.lo_deg},
                                 {"hi_deg", bin.hi_deg},
                                 {"nodes", bin.nodes},
                                 {"radiused_by_volume_pct", 100.0 * double(bin.radiused_by_volume) / double(bin.nodes)},
                                 {"radiused_by_area_pct", 100.0 * double(bin.radiused_by_area) / double(bin.nodes)}});
  for (const auto& [what, s] : r.timings) j["seconds"][what] = s;
  j["seconds"]["total"] = r.seconds;
  {
    const fs::path p = dir / "selection.json";
    std::ofstream f(p);
    f << j.dump(2) << "\n";
    if (!f) throw std::runtime_error("cannot write " + p.string());
    files.push_back(p);
  }
  if (r.options.nodes_csv) {
    // Per node of the passes' CL grid (model coordinates): the raw numbers
    // behind the choice maps.
    const fs::path p = dir / "nodes.csv";
    std::ofstream f(p);
    f << "x,y,z_ball,z_radiused,d,slope_deg,by_volume,by_area\n";
    const GridSpec& g = r.choice.grid;
    const auto& zb = r.ball.path.grid.z;
    const auto& zr = r.radiused.path.grid.z;
    auto name = [](Choice c) { return c == Choice::Ball ? "ball" : c == Choice::Radiused ? "radiused" : ""; };
    std::string out;
    char* at = nullptr;
    char line[256];
    auto num = [&](double v, int digits) {  // empty where NaN
      if (std::isfinite(v)) at += std::snprintf(at, 40, "%.*f", digits, v);
      *at++ = ',';
    };
    for (std::size_t k = 0; k < g.size(); ++k) {
      at = line;
      num(g.x(k % g.nx), 4);
      num(g.y(k / g.nx), 4);
      num(zb[k], 5);
      num(zr[k], 5);
      num(r.choice.d[k], 5);
      num(r.choice.slope_deg[k], 2);
      at += std::snprintf(at, 24, "%s,%s\n", name(r.choice.by_volume[k]), name(r.choice.by_area[k]));
      out.append(line, static_cast<std::size_t>(at - line));
      if (out.size() > (1u << 20)) f << std::exchange(out, {});
    }
    f << out;
    if (!f) throw std::runtime_error("cannot write " + p.string());
    files.push_back(p);
  }
  {
    const fs::path p = dir / "table_4_1.csv";
    std::ofstream f(p);
    f << "cutter,method,max_mm,min_mm,mean_mm,samples\n";
    for (const CutterRun* run : {&r.ball, &r.radiused}) {
      for (const auto& [method, s] : {std::pair<const char*, ScallopStats>{"cut_simulation", run->scallops.stats},
                                      {"estimate_2d", run->estimate_2d}})
        f << run->cutter.spec() << "," << method << "," << mm(s.max, 6) << "," << mm(s.min, 6) << "," << mm(s.mean, 6) << ","
          << s.samples << "\n";
    }
    if (!f) throw std::runtime_error("cannot write " + p.string());
    files.push_back(p);
  }
  {
    const fs::path p = dir / "slope_bins.csv";
    std::ofstream f(p);
    f << "lo_deg,hi_deg,nodes,radiused_by_volume_pct,radiused_by_area_pct\n";
    for (const auto& bin : r.profile.bins)
      if (bin.nodes)
        f << bin.lo_deg << "," << bin.hi_deg << "," << bin.nodes << ","
          << mm(100.0 * double(bin.radiused_by_volume) / double(bin.nodes), 2) << ","
          << mm(100.0 * double(bin.radiused_by_area) / double(bin.nodes), 2) << "\n";
    if (!f) throw std::runtime_error("cannot write " + p.string());
    files.push_back(p);
  }

  // Pictures: rendered and encoded side by side (they are independent).
  std::vector<std::function<void()>> pictures;
  const std::vector<MapCategory> cats = {{"ball " + ball + " removes more", category_colour(1)},
                                         {"radiused " + rad + " removes more", category_colour(2)}};
  auto choice_png = [&](const std::vector<Choice>& ch, const char* name, const std::string& title) {
    std::vector<int> c(ch.size());
    for (std::size_t k = 0; k < ch.size(); ++k) c[k] = static_cast<int>(ch[k]);
    CategoryMapOptions mo;
    mo.title = title;
    mo.subtitle = "d = ball centre z - corner centre z; radiused where d > d_base";
    mo.none_label = "off part";
    const fs::path p = dir / name;
    pictures.push_back([&r, &cats, p, c = std::move(c), mo] {
      write_png(p, render_category_map(map_grid(r.choice.grid), c, cats, mo));
    });
    files.push_back(p);
  };
  choice_png(r.choice.by_volume, "choice_volume.png", "Cutter removing more material (volume criterion)");
  choice_png(r.choice.by_area, "choice_area.png", "Cutter removing more material (area criterion)");
  // Colours span the scallops, not the corners neither cutter reaches: up
  // to three times the median pass-pair scallop (or the tolerance).
  std::vector<double> all;
  for (const CutterRun* run : {&r.ball, &r.radiused})
    for (double v : run->scallops.pair_scallop)
      if (std::isfinite(v)) all.push_back(v);
  double top = 0;
  if (!all.empty()) {
    const auto q = all.begin() + static_cast<std::ptrdiff_t>(all.size() / 2);
    std::nth_element(all.begin(), q, all.end());
    top = std::max({3 * *q, 3 * r.options.scallop_tol, 1e-3});
  }
  for (const CutterRun* run : {&r.ball, &r.radiused}) {
    std::vector<double> v(run->scallops.residual.size());
    std::vector<std::uint8_t> invalid(v.size(), 0);
    for (std::size_t k = 0; k < v.size(); ++k) {
      v[k] = std::clamp(run->scallops.residual[k], 0.0, top > 0 ? top : 1.0);
      invalid[k] = !std::isfinite(run->scallops.residual[k]);
      if (invalid[k]) v[k] = 0;
    }
    HeightMapOptions ho;
    ho.title = "Material left (machined - design) by " + run->cutter.description();
    ho.subtitle = "cut simulation, stepover " + mm(r.options.stepover, 3) + " mm; colours clipped at " + mm(top, 3) +
                  " mm (3 x the median scallop or the tolerance)";
    ho.z_min = 0;
    ho.z_max = top > 0 ? top : 1.0;
    ho.vertical_exaggeration = 0;
    const fs::path p = dir / ("scallop_" + safe(run->cutter.spec()) + ".png");
    pictures.push_back([&r, p, v = std::move(v), invalid = std::move(invalid), ho] {
      write_png(p, render_height_map(map_grid(r.design.grid), v, invalid, ho));
    });
    files.push_back(p);
  }
  {
    std::vector<int> c(r.min_scallop_choice.begin(), r.min_scallop_choice.end());
    const std::vector<MapCategory> mc = {{"ball " + ball + " leaves less", category_colour(1)},
                                         {"radiused " + rad + " leaves less", category_colour(2)},
                                         {"equal within 1 um", category_colour(0)}};
    CategoryMapOptions mo;
    mo.title = "Cutter leaving the smaller scallop";
    mo.subtitle = "scallop between each pair of passes (cut simulation), stepover " + mm(r.options.stepover, 3) + " mm";
    mo.none_label = "off part";
    const fs::path p = dir / "choice_min_scallop.png";
    pictures.push_back([&r, p, c = std::move(c), mc, mo] {
      write_png(p, render_category_map(map_grid(r.design.grid), c, mc, mo));
    });
    files.push_back(p);
  }
  std::atomic<std::size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&] {
    for (std::size_t k; (k = next++) < pictures.size();) {
      try {
        pictures[k]();
      } catch (...) {
        std::lock_guard lock(error_mutex);
        if (!error) error = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < std::max(1u, std::thread::hardware_concurrency()); ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
  return files;
}

}  // namespace cncstream::app
