// `cncstream clgrid PART.stl --tool SPEC --grid STEP [--bounds ...] [--floor Z] -o OUT.{csv,png,f32}`
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include "cli_common.hpp"
#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/height_field_io.hpp"
#include "cncstream/cam/raster.hpp"
#include "cncstream/image/height_map.hpp"
#include "commands.hpp"

namespace cncstream::app {

namespace {

// CSV: header x,y,z, one node per line, x varying fastest. Streamed by tile.
void write_csv(const ClEngine& engine, const GridSpec& spec, const std::string& out) {
  std::ofstream f(out, std::ios::binary);
  if (!f) throw std::runtime_error(out + ": cannot open for writing");
  f << "x,y,z\n";
  char buf[96];
  engine.compute_tiles(spec, [&](const ClTile& tile) {
    const GridSpec& g = tile.grid.spec;
    for (std::size_t j = 0; j < g.ny; ++j)
      for (std::size_t i = 0; i < g.nx; ++i) {
        const int n = std::snprintf(buf, sizeof buf, "%.6f,%.6f,%.6f\n", g.x(i), g.y(j), tile.grid.at(i, j));
        f.write(buf, n);
      }
  });
  if (!f) throw std::runtime_error(out + ": write failed");
}

// Raw float32 + sidecar, streamed by tile.
void write_f32(const ClEngine& engine, const GridSpec& spec, const std::string& out) {
  HeightFieldWriter w(out, spec);
  engine.compute_tiles(spec, [&](const ClTile& tile) { w.append(tile.grid.z); });
  w.finish();
}

// A shaded height map a person can look at (the whole grid in memory).
void write_png_map(const ClEngine& engine, const GridSpec& spec, const std::string& out, const std::string& title) {
  const ClGrid g = engine.compute(spec);
  MapGrid mg{spec.nx, spec.ny, spec.dx, spec.dy, spec.x0, spec.y0};
  HeightMapOptions ho;
  ho.title = title;
  ho.subtitle = engine.cutter().description() + ", grid " + std::to_string(spec.nx) + " x " + std::to_string(spec.ny);
  ho.max_map_pixels = 1000;
  write_png(out, render_height_map(mg, g.z, {}, ho));
}

}  // namespace

void register_clgrid(CLI::App& app, CommandRegistry& registry) {
  struct Opts {
    PartOptions part;
    std::string tool, bounds, out;
    double grid = 0;
    std::optional<double> floor;
    unsigned threads = 0;
  };
  auto o = std::make_shared<Opts>();
  auto* sub = app.add_subcommand("clgrid", "Compute the cutter-location (tool tip) height grid of an STL");
  sub->add_option("stl", o->part.stl, "STL file")->required();
  add_part_options(sub, o->part);
  sub->add_option("--tool", o->tool, "Cutter: flat:D, ball:D, bull:D:r")->required();
  sub->add_option("--grid", o->grid, "Grid step, mm")->required()->check(CLI::PositiveNumber);
  sub->add_option("--bounds", o->bounds, "X0,Y0,X1,Y1 in the STL's coordinates (default: XY box grown by the tool radius)");
  sub->add_option("--floor", o->floor, "Height where the tool touches nothing (default: the mesh's lowest z)");
  sub->add_option("--threads", o->threads, "Worker threads (0: all cores)");
  sub->add_option("-o,--output", o->out, "Output: .csv, .png or .f32")->required();
  registry.add(sub, [o] {
    const auto t0 = std::chrono::steady_clock::now();
    const Cutter cutter = parse_cutter_spec(o->tool);
    const std::string ext = std::filesystem::path(o->out).extension().string();
    if (ext != ".csv" && ext != ".png" && ext != ".f32")
      throw std::invalid_argument(o->out + ": unsupported output type '" + ext + "' (use .csv, .png or .f32)");
    const auto mesh = jobs::load_part(part_source(o->part));
    XYBounds b = default_bounds(*mesh, cutter);
    if (!o->bounds.empty()) {
      const auto v = parse_bounds(o->bounds);
      b = {v[0], v[1], v[2], v[3]};
    }
    const GridSpec spec = GridSpec::covering(b.x0, b.y0, b.x1, b.y1, o->grid, o->grid);
    ClOptions clo;
    clo.floor = o->floor;
    clo.threads = o->threads;
    const ClEngine engine(*mesh, cutter, clo);
    if (ext == ".csv") write_csv(engine, spec, o->out);
    else if (ext == ".f32") write_f32(engine, spec, o->out);
    else write_png_map(engine, spec, o->out, "CL surface (tool tip) of " + std::filesystem::path(o->part.stl).filename().string());
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::cout << "grid " << spec.nx << " x " << spec.ny << " = " << spec.size() << " nodes, step " << o->grid
              << " mm, floor " << engine.floor() << "; wrote " << o->out << " in " << s << " s\n";
    return 0;
  });
}

}  // namespace cncstream::app
