#include "cncstream/jobs/toolpath_job.hpp"

#include "cncstream/jobs/size_limits.hpp"

#include <oneapi/tbb/task_group.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <optional>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/row_spacing.hpp"
#include "cncstream/cam/thread_limit.hpp"
#include "cncstream/gcode/gcode_writer.hpp"
#include "cncstream/jobs/output_file.hpp"
#include "cncstream/jobs/work_setup.hpp"
#include "finishing_stage.hpp"
#include "job_operations.hpp"
#include "link_feed_job.hpp"
#include "job_run.hpp"
#include "job_text.hpp"
#include "rest_stage.hpp"
#include "roughing_stage.hpp"

namespace cncstream::jobs {

namespace {

// Share of the whole job at the start of each stage (measured on the plaque:
// the CL grid and the rows take most of it; roughing, when there is one,
// about as much again).
constexpr double kPathFrom = 0.05, kRoughFrom = 0.5, kGcodeFrom = 0.85, kWriteFrom = 0.97;

}  // namespace

std::string row_spacing_text(const cam::RasterPath& path) {
  if (path.stepover - path.stepover_min < 1e-9) return format_gcode_number(path.stepover, 4);
  return format_gcode_number(path.stepover_min, 4) + " to " + format_gcode_number(path.stepover, 4);
}

// A V-bit or tapered ball: as deep as a ball of its top diameter, and never
// deeper than its flutes (beyond them the shank rubs the wall).
double default_max_depth(const cam::Cutter& c) {
  if (!c.is_apt()) return std::min(c.profile_top(), c.radius);
  return c.type == cam::CutterType::Flat ? c.diameter() / 4 : c.radius;
}

ToolpathProgram generate_toolpath(const ToolpathParams& p, const JobControl& control) {
  ToolpathProgram r;
  JobRun run(control);
  cam::run_with_thread_limit(control.threads, [&] {
    r.cutter = p.cutter;
    const double end_of_gcode = p.output.empty() ? 1.0 : kWriteFrom;
    run.stage("load", 0, kPathFrom);
    auto t0 = std::chrono::steady_clock::now();
    const std::shared_ptr<const geometry::Mesh> mesh = load_part(p.part);
    if (control.warn) {
      const std::string w =
          units_warning(mesh->bounds(), p.part.units, p.cutter.diameter(), p.part.stl.empty() ? "the part" : p.part.stl);
      if (!w.empty()) control.warn(w);
    }
    r.facets = mesh->triangles.size();
    r.seconds_load = seconds_since(t0);

    // A rest machining takes the end of the tool path's share.
    const double rest_share = p.rest ? 0.12 : 0;
    const double path_to = (p.stock ? kRoughFrom : kGcodeFrom) - rest_share;
    run.stage("tool path", kPathFrom, path_to);
    t0 = std::chrono::steady_clock::now();
    cam::ClOptions clo;
    clo.floor = p.floor;
    clo.floor_is_lowest = true;  // no pass below the part's bottom (ClOptions)
    const cam::ClEngine engine(*mesh, r.cutter, clo);
    const geometry::Box3 box = mesh->bounds();
    const WorkSetup work = work_setup(box, p.origin, p.z_zero);
    const FinishSpacing spacing = finish_spacing(p);
    const bool along_x = p.direction != cam::RasterDirection::Y;
    cam::RasterOptions ro;
    ro.stepover = spacing.stepover;
    ro.step = spacing.step;
    ro.direction = p.direction;
    ro.tolerance = rows_tolerance(p);
    ro.lattice = work.lattice;
    const cam::XYBounds region = p.bounds.value_or(cam::default_bounds(*mesh, r.cutter));
    {
      // Rows across, points along (the raster's default step), before any is made.
      const double step = spacing.step > 0 ? spacing.step : std::min(spacing.stepover / 4, 0.1);
      const double w = region.x1 - region.x0, h = region.y1 - region.y0;
      check_grid_memory((along_x ? w : h) / step + 1, (along_x ? h : w) / spacing.stepover + 1, 48, step,
                        "the tool path");
    }
    const bool steep_shallow = p.strategy == FinishStrategy::SteepShallow;
    const bool by_slope = spacing.row_widest > 0;
    if (p.raster_grid) {
      if (steep_shallow || p.rest)
        throw std::invalid_argument("another CL engine makes only the raster finishing's grid: steep-and-shallow "
                                    "finishing and rest machining need the exact engine's point queries (use "
                                    "--strategy raster, without --rest)");
      ro.grid_source = [&](const cam::GridSpec& spec, const cam::Checkpoint&) { return p.raster_grid(*mesh, r.cutter, spec); };
    }
    // Operations that need nothing of the finishing run beside it: the
    // roughing's path when a roughing cutter is asked for (else whether one
    // is needed comes from the finishing), the rest machining. TBB gives
    // them the cores the finishing's serial stretches leave (the plaque's
    // roughing took 0.55-0.65 s after the finishing on 1.2 cores; its check
    // alone is left there, 0.25-0.3 s). They check for a stop; their
    // progress shows in their stage after the finishing.
    const cam::Checkpoint stop_only = [&run](double) { run.check(); };
    std::optional<RoughingStage> rough;
    std::optional<RestStage> rest;
    double rough_beside_s = 0, rest_beside_s = 0;
    tbb::task_group beside;
    r.stages_overlap = (p.stock && p.rough) || p.rest;
    if (p.stock && p.rough)
      beside.run([&] {
        const auto t = std::chrono::steady_clock::now();
        rough = roughing_from_stock(p, *mesh, work.offset, true, stop_only);
        rough_beside_s = seconds_since(t);
      });
    if (p.rest)
      beside.run([&] {
        const auto t = std::chrono::steady_clock::now();
        rest = plan_rest(p, *mesh, engine, region, work.lattice, stop_only);
        rest_beside_s = seconds_since(t);
      });

    // The slope of the ground, for the waterlines and the rows' spacing.
    std::optional<cam::ClGrid> ground;
    if (steep_shallow || by_slope) ground = ground_grid(engine, region, spacing, run.nested_checkpoint(0, 0.15));
    if (by_slope) {
      auto rows = std::make_shared<const cam::RowSpacing>(*ground, along_x, spacing.row_widest, spacing.row_angle);
      ro.stepover = spacing.row_widest;
      ro.row_gap = [rows](double va, double vb) { return rows->gap(va, vb); };
      // Along the rows, as for even rows at the narrowest spacing.
      if (!(ro.step > 0)) ro.step = std::min(spacing.stepover / 4, 0.1);
    } else {
      ro.keep_grid = true;  // for the preview, then let go
    }
    const double rows_to = steep_shallow ? 0.65 : 1.0;
    r.path = cam::build_raster(engine, region, ro, run.nested_checkpoint(ground ? 0.15 : 0, rows_to));
    r.preview = height_preview_from_grid(by_slope ? *ground : r.path.grid, r.path.bounds, work.offset);
    r.path.grid = cam::ClGrid{};
    if (steep_shallow) {
      add_waterlines(r, p, engine, *ground, work.lattice, spacing, run.nested_checkpoint(rows_to, 1.0));
    } else {
      r.finish_pieces = raster_as_one_cut(r.path);
    }
    r.seconds_path = seconds_since(t0);

    if (p.rest) run.stage("rest machining", path_to, path_to + rest_share);
    beside.wait();
    r.seconds_rest = rest_beside_s;

    if (p.stock) {
      run.stage("roughing", kRoughFrom, kGcodeFrom);
      t0 = std::chrono::steady_clock::now();
      if (!rough) rough = roughing_from_stock(p, *mesh, work.offset, false, run.checkpoint());
      check_roughing(*rough, p, *mesh, r.finish_pieces, work.offset, run.checkpoint());
      r.seconds_rough = rough_beside_s + seconds_since(t0);
    }

    run.stage("G-code", kGcodeFrom, end_of_gcode);
    t0 = std::chrono::steady_clock::now();
    r.work_offset = work.offset;
    r.work_mesh = *mesh;
    r.work_mesh.translate(work.offset);
    MachiningParams mp;
    mp.feed = p.feed;
    mp.plunge_feed = p.plunge_feed;
    mp.rpm = p.rpm;
    mp.safe_z = p.safe_z.value_or(box.hi.z + work.offset.z + 5.0);
    if (p.arcs) {
      ArcFitOptions arcs;
      arcs.tolerance = p.tolerance;
      arcs.controller_arc_tolerance = p.controller_arc_tolerance;
      arcs.material_below = true;
      // Waterlines keep the part on their right (climb milling with M3).
      arcs.material_right = true;
      mp.arcs = arcs;
    }
    const XYOrigin xy = p.origin;
    const ZZero zz = p.z_zero;
    mp.header_comments = {
        steep_shallow ? "cncstream steep-and-shallow finishing" : "cncstream raster finishing",
        "part: " + p.part.stl + " (" + std::to_string(r.facets) + " facets)",
        "tool: " + r.cutter.description() + " [" + r.cutter.spec() + "]",
        "stepover " + row_spacing_text(r.path) + " mm along " +
            (p.direction == cam::RasterDirection::Y ? "Y" : "X") + ", step " + format_gcode_number(r.path.step, 4) +
            " mm, tolerance " + format_gcode_number(p.tolerance, 4) + " mm" +
            (p.arcs ? std::string(", arcs for a controller arc tolerance of ")
                          .append(format_gcode_number(p.controller_arc_tolerance, 4))
                          .append(" mm")
                    : std::string(", no arcs")),
        std::string("work origin: XY at ") +
            (xy == XYOrigin::PartMin ? "part minimum" : xy == XYOrigin::PartCenter ? "part centre" : "model origin") +
            ", Z0 at " + (zz == ZZero::PartTop ? "part top" : zz == ZZero::PartBottom ? "part bottom" : "model origin"),
    };
    if (p.grid_note) mp.header_comments.push_back(p.grid_note());
    if (!rough && !rest) {
      r.gcode = pieces_program(r.finish_pieces, work.offset, mp, &r.stats);
      r.operations.push_back(finishing_summary(r, p, r.stats));
    } else {
      compose_job(r, p, rough ? &*rough : nullptr, rest ? &*rest : nullptr, mp);
    }
    if (p.link && p.link->bytes_per_second > 0) limit_feed_to_link(r, *p.link);
    r.seconds_gcode = seconds_since(t0);

    if (!p.output.empty()) {
      run.stage("write", kWriteFrom, 1.0);
      write_text_file_atomically(p.output, r.gcode);
    }
  });
  run.finish();
  return r;
}

}  // namespace cncstream::jobs
