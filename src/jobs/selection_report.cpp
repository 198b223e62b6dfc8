#include "cncstream/jobs/selection_report.hpp"

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <fstream>
#include <functional>
#include <iterator>
#include <stdexcept>
#include <string>
#include <utility>

#include "cncstream/cam/thread_limit.hpp"
#include "cncstream/image/category_map.hpp"
#include "cncstream/image/height_map.hpp"
#include "cncstream/image/image.hpp"
#include "cncstream/jobs/output_file.hpp"
#include "fixed_text.hpp"
#include "job_run.hpp"
#include "job_text.hpp"

namespace cncstream::jobs {

namespace fs = std::filesystem;

namespace {

image::MapGrid map_grid(const cam::GridSpec& g) { return {g.nx, g.ny, g.dx, g.dy, g.x0, g.y0}; }

std::string mm(double v, int digits = 4) { return fixed_text(v, digits); }

// A report file through `fill(stream)`, whole or not at all.
void write_report_file(const fs::path& p, const std::function<void(std::ostream&)>& fill) {
  write_file_atomically(p, [&](const fs::path& file) {
    std::ofstream f(file);
    fill(f);
    f.close();
    if (!f) throw std::runtime_error("cannot write " + p.string());
  });
}

std::string json_text(const SelectionResult& r) {
  nlohmann::json j;
  j["part"] = r.params.part.stl;
  j["facets"] = r.facets;
  j["stepover_mm"] = r.params.stepover;
  j["step_mm"] = r.params.step;
  j["direction"] = r.params.direction == cam::RasterDirection::Y ? "y" : "x";
  j["cutters"] = {{"ball", r.pair.ball.spec()}, {"radiused", r.pair.radiused.spec()}};
  if (r.tapered) j["cutters"]["tapered"] = r.tapered->cutter.spec();
  j["d_base_mm"] = {{"volume", r.choice.d_base_volume}, {"area", r.choice.d_base_area}};
  j["switch_deg"] = {{"volume_plane", cam::switch_angle(r.pair.rc(), r.choice.d_base_volume) * 180 / M_PI},
                     {"area_plane", cam::switch_angle(r.pair.rc(), r.choice.d_base_area) * 180 / M_PI},
                     {"volume_measured", std::isfinite(r.profile.switch_deg_volume) ? nlohmann::json(r.profile.switch_deg_volume) : nlohmann::json()},
                     {"area_measured", std::isfinite(r.profile.switch_deg_area) ? nlohmann::json(r.profile.switch_deg_area) : nlohmann::json()}};
  const double on = std::max<double>(1, double(r.choice.on_part));
  j["share_radiused_pct"] = {{"volume", 100 * double(r.choice.radiused_by_volume) / on},
                             {"area", 100 * double(r.choice.radiused_by_area) / on}};
  j["analysis_nodes_on_part"] = r.choice.on_part;
  auto stats = [](const cam::ScallopStats& s) {
    return nlohmann::json{{"max_mm", s.max}, {"min_mm", s.min}, {"mean_mm", s.mean}, {"samples", s.samples}};
  };
  for (const CutterRun* run : r.runs()) {
    j["scallop"][run->cutter.spec()] = {{"cut_simulation", stats(run->scallops.stats)},
                                        {"estimate_2d", stats(run->estimate_2d)}};
    const cam::UnreachableStats& u = run->scallops.unreachable_stats;
    if (u.computed)
      j["unreachable"][run->cutter.spec()] = {{"max_mm", u.max},
                                              {"at_work_xy", {u.max_x + r.work_offset.x, u.max_y + r.work_offset.y}},
                                              {"mean_mm", u.mean},
                                              {"share_above_min_pct", 100 * u.share},
                                              {"min_mm", cam::kUnreachableMin}};
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
  return j.dump(2) + "\n";
}

// Per node of the passes' CL grid (model coordinates): the raw numbers behind
// the choice maps.
void write_nodes_csv(const SelectionResult& r, std::ostream& f) {
  f << "x,y,z_ball,z_radiused,d,slope_deg,by_volume,by_area\n";
  const cam::GridSpec& g = r.choice.grid;
  const auto& zb = r.ball.path.grid.z;
  const auto& zr = r.radiused.path.grid.z;
  auto name = [](cam::Choice c) { return c == cam::Choice::Ball ? "ball" : c == cam::Choice::Radiused ? "radiused" : ""; };
  std::string out;
  auto at = std::back_inserter(out);
  auto num = [&](double v, int digits) {  // empty where NaN
    if (std::isfinite(v)) at = fmt::format_to(at, "{:.{}f}", v, digits);
    *at++ = ',';
  };
  for (std::size_t k = 0; k < g.size(); ++k) {
    num(g.x(k % g.nx), 4);
    num(g.y(k / g.nx), 4);
    num(zb[k], 5);
    num(zr[k], 5);
    num(r.choice.d[k], 5);
    num(r.choice.slope_deg[k], 2);
    at = fmt::format_to(at, "{},{}\n", name(r.choice.by_volume[k]), name(r.choice.by_area[k]));
    if (out.size() > (1u << 20)) f << std::exchange(out, {});
  }
  f << out;
}

}  // namespace

std::vector<fs::path> write_selection_report(const SelectionResult& r, const fs::path& dir,
                                             const SelectionReportOptions& options, const JobControl& control) {
  JobRun run(control);
  std::vector<fs::path> files;
  cam::run_with_thread_limit(control.threads, [&] {
    run.stage("report", 0, 1);
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) throw std::runtime_error("cannot create report folder " + dir.string() + ": " + ec.message());
    const std::string ball = r.pair.ball.spec(), rad = r.pair.radiused.spec();
    // selection.json is written last and vouches for the folder: an earlier report's goes first.
    fs::remove(dir / "selection.json", ec);
    const auto safe = safe_name;

    // Numbers: JSON (written last) and CSV.
    const fs::path json_path = dir / "selection.json";
    files.push_back(json_path);
    if (options.nodes_csv) {
      const fs::path p = dir / "nodes.csv";
      write_report_file(p, [&](std::ostream& f) { write_nodes_csv(r, f); });
      files.push_back(p);
      run.check();
    }
    {
      const fs::path p = dir / "table_4_1.csv";
      write_report_file(p, [&](std::ostream& f) {
        f << "cutter,method,max_mm,min_mm,mean_mm,samples\n";
        for (const CutterRun* cr : r.runs()) {
          for (const auto& [method, s] : {std::pair<const char*, cam::ScallopStats>{"cut_simulation", cr->scallops.stats},
                                          {"estimate_2d", cr->estimate_2d}})
            f << cr->cutter.spec() << "," << method << "," << mm(s.max, 6) << "," << mm(s.min, 6) << "," << mm(s.mean, 6)
              << "," << s.samples << "\n";
        }
      });
      files.push_back(p);
    }
    {
      const fs::path p = dir / "slope_bins.csv";
      write_report_file(p, [&](std::ostream& f) {
        f << "lo_deg,hi_deg,nodes,radiused_by_volume_pct,radiused_by_area_pct\n";
        for (const auto& bin : r.profile.bins)
          if (bin.nodes)
            f << bin.lo_deg << "," << bin.hi_deg << "," << bin.nodes << ","
              << mm(100.0 * double(bin.radiused_by_volume) / double(bin.nodes), 2) << ","
              << mm(100.0 * double(bin.radiused_by_area) / double(bin.nodes), 2) << "\n";
      });
      files.push_back(p);
    }

    // Pictures: rendered and encoded side by side (they are independent).
    std::vector<std::function<void()>> pictures;
    const std::vector<image::MapCategory> cats = {{"ball " + ball + " removes more", image::category_colour(1)},
                                           {"radiused " + rad + " removes more", image::category_colour(2)}};
    auto png = [](const fs::path& p, const image::RgbImage& image) {
      write_file_atomically(p, [&](const fs::path& file) { image::write_png(file, image); });
    };
    auto choice_png = [&](const std::vector<cam::Choice>& ch, const char* name, const std::string& title) {
      std::vector<int> c(ch.size());
      for (std::size_t k = 0; k < ch.size(); ++k) c[k] = static_cast<int>(ch[k]);
      image::CategoryMapOptions mo;
      mo.title = title;
      mo.subtitle = "d = ball centre z - corner centre z; radiused where d > d_base";
      mo.none_label = "off part";
      const fs::path p = dir / name;
      pictures.push_back([&r, &cats, png, p, c = std::move(c), mo] {
        png(p, image::render_category_map(map_grid(r.choice.grid), c, cats, mo));
      });
      files.push_back(p);
    };
    choice_png(r.choice.by_volume, "choice_volume.png", "Cutter removing more material (volume criterion)");
    choice_png(r.choice.by_area, "choice_area.png", "Cutter removing more material (area criterion)");
    // Colours span the scallops, not the corners neither cutter reaches: up
    // to three times the median pass-pair scallop (or the tolerance).
    std::vector<double> all;
    for (const CutterRun* cr : {&r.ball, &r.radiused})
      for (double v : cr->scallops.pair_scallop)
        if (std::isfinite(v)) all.push_back(v);
    double top = 0;
    if (!all.empty()) {
      const auto q = all.begin() + static_cast<std::ptrdiff_t>(all.size() / 2);
      std::nth_element(all.begin(), q, all.end());
      top = std::max({3 * *q, 3 * r.params.scallop_tol, 1e-3});
    }
    for (const CutterRun* cr : {&r.ball, &r.radiused}) {
      std::vector<double> v(cr->scallops.residual.size());
      std::vector<std::uint8_t> invalid(v.size(), 0);
      for (std::size_t k = 0; k < v.size(); ++k) {
        v[k] = std::clamp(cr->scallops.residual[k], 0.0, top > 0 ? top : 1.0);
        invalid[k] = !std::isfinite(cr->scallops.residual[k]);
        if (invalid[k]) v[k] = 0;
      }
      image::HeightMapOptions ho;
      ho.title = "Material left (machined - design) by " + cr->cutter.description();
      ho.subtitle = "cut simulation, stepover " + mm(r.params.stepover, 3) + " mm; colours clipped at " + mm(top, 3) +
                    " mm (3 x the median scallop or the tolerance)";
      ho.z_min = 0;
      ho.z_max = top > 0 ? top : 1.0;
      ho.vertical_exaggeration = 0;
      const fs::path p = dir / ("scallop_" + safe(cr->cutter.spec()) + ".png");
      pictures.push_back([&r, png, p, v = std::move(v), invalid = std::move(invalid), ho] {
        png(p, image::render_height_map(map_grid(r.design.grid), v, invalid, ho));
      });
      files.push_back(p);
    }
    {
      std::vector<int> c(r.min_scallop_choice.begin(), r.min_scallop_choice.end());
      const std::vector<image::MapCategory> mc = {{"ball " + ball + " leaves less", image::category_colour(1)},
                                           {"radiused " + rad + " leaves less", image::category_colour(2)},
                                           {"equal within 1 um", image::category_colour(0)}};
      image::CategoryMapOptions mo;
      mo.title = "Cutter leaving the smaller scallop";
      mo.subtitle = "scallop between each pair of passes (cut simulation), stepover " + mm(r.params.stepover, 3) + " mm";
      mo.none_label = "off part";
      const fs::path p = dir / "choice_min_scallop.png";
      pictures.push_back([&r, png, p, c = std::move(c), mc, mo] {
        png(p, image::render_category_map(map_grid(r.design.grid), c, mc, mo));
      });
      files.push_back(p);
    }
    std::atomic<std::size_t> done{0};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pictures.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t k = range.begin(); k != range.end(); ++k) {
                          run.check();
                          pictures[k]();
                          run.within(double(++done) / double(pictures.size() + 1));
                        }
                      });
    run.check();
    const std::string json = json_text(r);
    write_report_file(json_path, [&](std::ostream& f) { f << json; });
  });
  run.finish();
  return files;
}

}  // namespace cncstream::jobs
