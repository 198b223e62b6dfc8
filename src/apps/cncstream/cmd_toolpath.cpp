// `cncstream toolpath PART.stl --tool SPEC --stepover S ... [--engine gl] -o part.nc`
#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <iostream>
#include <memory>

#include "cncstream/gl/gl_cl_engine.hpp"
#include "cncstream/jobs/toolpath_job.hpp"
#include "commands.hpp"
#include "long_job.hpp"
#include "tool_choice.hpp"
#include "toolpath_options.hpp"

namespace cncstream::app {

namespace {

struct DepthBufferGrids {
  std::size_t grids = 0, nodes = 0;
  double seconds = 0, lift = 0;
  std::string renderer;
};

// The raster's CL grids from the GL engine, lifted by its bound so the rows
// stand on or above the exact CL (the raster raises a node still below).
void use_depth_buffer(jobs::ToolpathParams& params, double tolerance, const std::shared_ptr<DepthBufferGrids>& stats) {
  gl::GlClOptions glo;
  glo.tolerance = tolerance;
  glo.floor = params.floor;
  glo.lift_to_bound = true;
  params.raster_grid = [glo, stats](const geometry::Mesh& mesh, const cam::Cutter& cutter, const cam::GridSpec& spec) {
    const auto t0 = std::chrono::steady_clock::now();
    gl::GlClStats st;
    cam::ClGrid g = gl::compute_cl_grid_gl(mesh, cutter, spec, glo, &st);
    stats->grids += 1;
    stats->nodes += spec.size();
    stats->seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    stats->lift = std::max(stats->lift, st.lifted);
    stats->renderer = st.renderer;
    return g;
  };
  params.grid_note = [tolerance, stats] {
    return fmt::format("CL grid of the rows: the depth buffer [GL engine], tessellation tolerance {:g} mm, lifted "
                       "{:.4f} mm so no node is below the exact surface",
                       tolerance, stats->lift);
  };
}

}  // namespace

void register_toolpath(CLI::App& app, CommandRegistry& registry) {
  struct Opts {
    ToolpathOptions tp;
    std::string out;
    std::string engine = "exact";
    std::optional<double> gl_tolerance;
    ProgressMode progress = ProgressMode::Auto;
  };
  auto o = std::make_shared<Opts>();
  auto* sub = app.add_subcommand("toolpath", "Generate a raster finishing tool path (G-code) from an STL");
  sub->add_option("stl", o->tp.part.stl, "STL file")->required();
  add_toolpath_options(sub, o->tp);
  sub->add_option("-o,--output", o->out, "G-code file to write")->required();
  sub->add_option("--engine", o->engine,
                  "The raster finishing's CL grid: exact (the CPU engine) or gl (the thesis's depth buffer through "
                  "headless EGL, lifted by its tessellation bound so no node is below the exact surface; "
                  "--strategy raster, no --rest)")
      ->check(CLI::IsMember({"exact", "gl"}))->capture_default_str();
  sub->add_option("--gl-tolerance", o->gl_tolerance, "GL engine: chordal tolerance of the offset tessellation, mm "
                                                     "(default 0.05)")
      ->check(CLI::PositiveNumber);
  add_progress_option(sub, o->progress);
  registry.add(sub, [o] {
    const auto t0 = std::chrono::steady_clock::now();
    const auto feeds_request = resolve_tool_options(o->tp);
    jobs::ToolpathParams params = toolpath_params(o->tp);
    const jobs::FeedsPlan feeds = apply_feeds(params, feeds_request);
    params.output = o->out;
    if (o->engine != "gl" && o->gl_tolerance) throw std::invalid_argument("--gl-tolerance applies to --engine gl only");
    auto gl_stats = std::make_shared<DepthBufferGrids>();
    if (o->engine == "gl") use_depth_buffer(params, o->gl_tolerance.value_or(0.05), gl_stats);
    LongJob job(o->progress, o->tp.threads);
    std::optional<jobs::ToolpathProgram> program;
    try {
      program = jobs::generate_toolpath(params, job.control());
    } catch (const jobs::Cancelled&) {
      return job.interrupted_exit(o->out + " not written");
    }
    job.clear_progress();
    const jobs::ToolpathProgram& r = *program;
    std::cout << toolpath_report(r) << jobs::feeds_plan_text(feeds, r);
    if (gl_stats->grids > 0)
      std::cout << "CL grid: the depth buffer (" << gl_stats->renderer << "), " << gl_stats->grids << " grid"
                << (gl_stats->grids == 1 ? "" : "s") << " of " << gl_stats->nodes << " nodes in " << gl_stats->seconds
                << " s, lifted " << gl_stats->lift << " mm; " << r.path.raised_to_exact
                << " nodes were still below the exact surface (beside walls) and were raised onto it\n";
    std::cout << "wrote " << o->out << " in "
              << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() << " s total\n";
    return 0;
  });
}

}  // namespace cncstream::app
