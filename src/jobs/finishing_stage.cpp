#include "finishing_stage.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "cncstream/cam/slope_map.hpp"
#include "cncstream/cam/steep_shallow.hpp"
#include "cncstream/cam/waterline.hpp"
#include "cncstream/gcode/finishing_program.hpp"

namespace cncstream::jobs {

namespace {

constexpr double kOverlapDeg = 10;  // the split's overlap either side of the steep angle

double radians(double deg) { return deg * std::numbers::pi / 180; }

}  // namespace

FinishSpacing finish_spacing(const ToolpathParams& p) {
  if (!(p.steep_angle > 0 && p.steep_angle < 90))
    throw std::invalid_argument(fmt::format("steep angle {} must be between 0 and 90 degrees", p.steep_angle));
  FinishSpacing s;
  s.stepover = p.stepover;
  s.step = p.step;
  const double rk = p.cutter.corner_radius;
  // The waterlines' grid places their contours (the engine makes them
  // exact): fine enough to follow a ball's curvature.
  s.grid_step = std::clamp(p.cutter.radius / 4, 0.05, 0.25);
  s.z_step = p.stepover;
  if (!p.scallop) return s;
  const double h = *p.scallop;
  const bool vbit = p.cutter.type == cam::CutterType::VBit;
  if (!(rk > 0) && !vbit)
    throw std::invalid_argument("a scallop height needs a ball, bull-nose, tapered ball or V-bit (a flat end leaves "
                                "terraces, not scallops): give --stepover instead");
  // A tapered ball's scallop comes from its ball tip (rk), not its top
  // diameter. A V-bit's passes d apart leave a V ridge between their flat
  // tips: (d - tip) / 2 wide, as high as the cone rises over that.
  const double spacing = vbit ? 2 * p.cutter.tip_radius + 2 * h * std::tan(radians(p.cutter.half_angle_deg))
                              : std::sqrt(8 * rk * h);
  const bool split = p.strategy == FinishStrategy::SteepShallow;
  const double row_angle = split ? std::min(89.0, p.steep_angle + kOverlapDeg) : p.steep_angle;
  s.stepover = std::cos(radians(row_angle)) * spacing;
  s.row_widest = spacing;
  // Spaced row by row, the rows answer for the ground up to the steep
  // angle only: every node steeper than it has a waterline beside it
  // (measured by ScallopBound: the overlap would cost 7 % more lines).
  s.row_angle = radians(p.steep_angle);
  s.z_step = std::sin(radians(std::max(1.0, p.steep_angle - kOverlapDeg))) * spacing;
  // Along the rows the samples must follow the surface: the raster's
  // default, a quarter of the stepover, at most 0.1 mm.
  s.step = p.step;
  return s;
}

cam::ClGrid ground_grid(const cam::ClEngine& engine, const cam::XYBounds& region, const FinishSpacing& spacing,
                   const cam::Checkpoint& checkpoint) {
  const cam::GridSpec spec = cam::GridSpec::covering(region.x0, region.y0, region.x1, region.y1, spacing.grid_step,
                                           spacing.grid_step);
  return engine.compute(spec, checkpoint);
}

void add_waterlines(ToolpathProgram& r, const ToolpathParams& p, const cam::ClEngine& engine, const cam::ClGrid& grid,
                    const cam::XYLattice& lattice, const FinishSpacing& spacing, const cam::Checkpoint& checkpoint) {
  const cam::SlopeMap slope(grid);
  cam::WaterlineOptions wo;
  wo.z_step = spacing.z_step;
  if (spacing.row_widest > 0) {
    // By the scallop: each band as the walls in it allow.
    wo.wall_spacing = spacing.row_widest;
    wo.wall_angle_deg = std::max(1.0, p.steep_angle - kOverlapDeg);
  }
  wo.steep_angle_deg = p.steep_angle;
  wo.tolerance = p.tolerance;
  wo.lattice = lattice;
  // Half the tolerance merges straight stretches; arcs take the curves.
  wo.simplify_tolerance = p.tolerance / 2;
  wo.sample_step = std::min(0.05, spacing.grid_step / 2);
  const cam::WaterlinePath w = cam::build_waterline(engine, grid, slope, wo, cam::checkpoint_part(checkpoint, 0, 0.95));
  const cam::SteepSkip shallow = cam::skip_steep(raster_as_one_cut(r.path), slope, radians(p.steep_angle));
  r.finish_pieces = w.pieces;
  r.finish_pieces.insert(r.finish_pieces.end(), shallow.pieces.begin(), shallow.pieces.end());
  r.waterline_pieces = w.pieces.size();
  r.waterline_levels = w.levels.size();
  r.waterline_step = w.step_min;
  r.waterline_step_max = w.step_max;
  r.steep_bridges = shallow.bridges;
  if (checkpoint) checkpoint(1.0);
}

}  // namespace cncstream::jobs
