// `cncstream clgrid PART.stl --tool SPEC --grid STEP [--bounds ...] [--floor Z]
//  [--engine exact|gl [--gl-tolerance T] [--trim]] -o OUT.{csv,png,f32}`
#include <fmt/core.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>

#include "cli_common.hpp"
#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/height_field_io.hpp"
#include "cncstream/cam/raster.hpp"
#include "cncstream/gl/gl_cl_engine.hpp"
#include "cncstream/image/height_map.hpp"
#include "cncstream/jobs/output_file.hpp"
#include "commands.hpp"
#include "long_job.hpp"

namespace cncstream::app {

namespace {

// The grid's progress and stop (from the engine's workers): throws
// jobs::Cancelled on a stop request.
cam::Checkpoint grid_checkpoint(const jobs::JobControl& control) {
  return [&control](double fraction) {
    if (control.stop.stop_requested()) throw jobs::Cancelled();
    if (control.progress) control.progress("CL grid", fraction);
  };
}

// CSV: header x,y,z, one node per line, x varying fastest. Streamed by tile.
void write_csv(const cam::ClEngine& engine, const cam::GridSpec& spec, const std::filesystem::path& out,
               const jobs::JobControl& control) {
  std::ofstream f(out, std::ios::binary);
  if (!f) throw std::runtime_error(out.string() + ": cannot open for writing");
  f << "x,y,z\n";
  std::string row;
  engine.compute_tiles(spec, [&](const cam::ClTile& tile) {
    const cam::GridSpec& g = tile.grid.spec;
    for (std::size_t j = 0; j < g.ny; ++j) {
      row.clear();
      for (std::size_t i = 0; i < g.nx; ++i)
        fmt::format_to(std::back_inserter(row), "{:.6f},{:.6f},{:.6f}\n", g.x(i), g.y(j), tile.grid.at(i, j));
      f << row;
    }
  }, grid_checkpoint(control));
  f.close();
  if (!f) throw std::runtime_error(out.string() + ": write failed");
}

// Raw float32 + sidecar, streamed by tile. The sidecar is renamed beside the
// final name before the data file is (write_file_atomically renames it last).
void write_f32(const cam::ClEngine& engine, const cam::GridSpec& spec, const std::filesystem::path& out,
               const std::filesystem::path& final_path, const jobs::JobControl& control) {
  cam::HeightFieldWriter w(out, spec);
  engine.compute_tiles(spec, [&](const cam::ClTile& tile) { w.append(tile.grid.z); }, grid_checkpoint(control));
  w.finish();
  if (out != final_path) std::filesystem::rename(cam::height_field_sidecar(out), cam::height_field_sidecar(final_path));
}

// A shaded height map a person can look at (the whole grid in memory).
void write_png_map(const cam::ClEngine& engine, const cam::GridSpec& spec, const std::filesystem::path& out,
                   const std::string& title, const jobs::JobControl& control) {
  const cam::ClGrid g = engine.compute(spec, grid_checkpoint(control));
  image::MapGrid mg{spec.nx, spec.ny, spec.dx, spec.dy, spec.x0, spec.y0};
  image::HeightMapOptions ho;
  ho.title = title;
  ho.subtitle = engine.cutter().description() + ", grid " + std::to_string(spec.nx) + " x " + std::to_string(spec.ny);
  ho.max_map_pixels = 1000;
  image::write_png(out, image::render_height_map(mg, g.z, {}, ho));
}

// The GL engine's whole grid, written in the same formats as the exact
// engine's (same nodes, same CSV and float32 layout).
void write_grid(const cam::ClGrid& g, const std::string& ext, const std::filesystem::path& out,
                const std::filesystem::path& final_path, const std::string& title, const std::string& subtitle) {
  const cam::GridSpec& spec = g.spec;
  if (ext == ".csv") {
    std::ofstream f(out, std::ios::binary);
    if (!f) throw std::runtime_error(out.string() + ": cannot open for writing");
    f << "x,y,z\n";
    std::string row;
    for (std::size_t j = 0; j < spec.ny; ++j) {
      row.clear();
      for (std::size_t i = 0; i < spec.nx; ++i)
        fmt::format_to(std::back_inserter(row), "{:.6f},{:.6f},{:.6f}\n", spec.x(i), spec.y(j), g.at(i, j));
      f << row;
    }
    f.close();
    if (!f) throw std::runtime_error(out.string() + ": write failed");
  } else if (ext == ".f32") {
    cam::write_height_field(out, spec, g.z);
    if (out != final_path) std::filesystem::rename(cam::height_field_sidecar(out), cam::height_field_sidecar(final_path));
  } else {
    image::MapGrid mg{spec.nx, spec.ny, spec.dx, spec.dy, spec.x0, spec.y0};
    image::HeightMapOptions ho;
    ho.title = title;
    ho.subtitle = subtitle;
    ho.max_map_pixels = 1000;
    image::write_png(out, image::render_height_map(mg, g.z, {}, ho));
  }
}

}  // namespace

void register_clgrid(CLI::App& app, CommandRegistry& registry) {
  struct Opts {
    PartOptions part;
    std::string tool, bounds, out;
    double grid = 0;
    std::optional<double> floor;
    unsigned threads = 0;
    std::string engine = "exact";
    std::optional<double> gl_tolerance;
    bool trim = false;
    ProgressMode progress = ProgressMode::Auto;
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
  sub->add_option("--engine", o->engine,
                  "exact: the exact CPU engine; gl: the thesis's depth buffer (OpenGL 3.3 through headless EGL)")
      ->check(CLI::IsMember({"exact", "gl"}));
  sub->add_option("--gl-tolerance", o->gl_tolerance,
                  "GL engine: chordal tolerance of the offset tessellation, mm (default 0.05; llvmpipe time grows about as tolerance^-1.5); nodes are at most this below the exact surface")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--trim", o->trim, "GL engine: the thesis's bounding-space trimming (can gouge: shows what it does)");
  sub->add_option("-o,--output", o->out, "Output: .csv, .png or .f32")->required();
  add_progress_option(sub, o->progress);
  registry.add(sub, [o] {
    const auto t0 = std::chrono::steady_clock::now();
    const cam::Cutter cutter = cam::parse_cutter_spec(o->tool);
    const std::string ext = std::filesystem::path(o->out).extension().string();
    if (ext != ".csv" && ext != ".png" && ext != ".f32")
      throw std::invalid_argument(o->out + ": unsupported output type '" + ext + "' (use .csv, .png or .f32)");
    const auto mesh = jobs::load_part(part_source(o->part));
    cam::XYBounds b = cam::default_bounds(*mesh, cutter);
    if (!o->bounds.empty()) {
      const auto v = parse_bounds(o->bounds);
      b = {v[0], v[1], v[2], v[3]};
    }
    const cam::GridSpec spec = cam::GridSpec::covering(b.x0, b.y0, b.x1, b.y1, o->grid, o->grid);
    if (o->engine != "gl" && (o->gl_tolerance || o->trim))
      throw std::invalid_argument("--gl-tolerance and --trim apply to --engine gl only");
    const std::string title = "CL surface (tool tip) of " + std::filesystem::path(o->part.stl).filename().string();
    if (o->engine == "gl") {
      gl::GlClOptions glo;
      if (o->gl_tolerance) glo.tolerance = *o->gl_tolerance;
      glo.trim = o->trim;
      glo.floor = o->floor;
      gl::GlClStats st;
      const cam::ClGrid g = gl::compute_cl_grid_gl(*mesh, cutter, spec, glo, &st);
      std::string subtitle = cutter.description();
      subtitle.append(", depth buffer, tolerance ");
      subtitle.append(fmt::format("{:g} mm{}", glo.tolerance, glo.trim ? ", trimmed" : ""));
      jobs::write_file_atomically(o->out, [&](const std::filesystem::path& file) {
        write_grid(g, ext, file, o->out, title, subtitle);
      });
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::cout << "grid " << spec.nx << " x " << spec.ny << " = " << spec.size() << " nodes, step " << o->grid
                << " mm, floor " << g.floor << "; GL engine (" << st.renderer << "), tolerance " << glo.tolerance
                << " mm" << (glo.trim ? ", trimmed" : "") << ", " << st.triangles << " triangles in " << st.tiles
                << " tile(s); wrote " << o->out << " in " << s << " s\n";
      return 0;
    }
    cam::ClOptions clo;
    clo.floor = o->floor;
    clo.threads = o->threads;
    LongJob job(o->progress, 0);  // the engine's own --threads
    const jobs::JobControl control = job.control();
    double floor_z = 0;
    try {
      if (control.stop.stop_requested()) throw jobs::Cancelled();
      const cam::ClEngine engine(*mesh, cutter, clo);
      floor_z = engine.floor();
      jobs::write_file_atomically(o->out, [&](const std::filesystem::path& file) {
        if (ext == ".csv") write_csv(engine, spec, file, control);
        else if (ext == ".f32") write_f32(engine, spec, file, o->out, control);
        else write_png_map(engine, spec, file, title, control);
      });
      if (control.progress) control.progress("done", 1);
    } catch (const jobs::Cancelled&) {
      return job.interrupted_exit(o->out + " not written");
    }
    job.clear_progress();
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::cout << "grid " << spec.nx << " x " << spec.ny << " = " << spec.size() << " nodes, step " << o->grid
              << " mm, floor " << floor_z << "; wrote " << o->out << " in " << s << " s\n";
    return 0;
  });
}

}  // namespace cncstream::app
