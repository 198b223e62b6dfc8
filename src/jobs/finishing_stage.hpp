#pragma once
// The finishing operation's spacing (from the scallop height when one is
// asked for) and its steep-and-shallow split. Private to the jobs layer.
#include "cncstream/cam/checkpoint.hpp"
#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/jobs/toolpath_job.hpp"

namespace cncstream::jobs {

struct FinishSpacing {
  double stepover = 0;     // between rows
  double step = 0;         // along rows (0: the raster's default)
  double z_step = 0;       // between waterline levels
  double grid_step = 0;    // of the waterlines' CL grid (and the rows' slope)
  // With a scallop height: rows spaced by the slope across them
  // (row_spacing.hpp), `row_widest` apart over level ground and down to
  // `stepover` = cos(row_angle) * row_widest; 0 without one (even rows).
  double row_widest = 0;
  double row_angle = 0;  // radians
};

// With a scallop height H and a cutter of corner radius rk, a pass spacing
// d leaves cusps of d^2 / (8 rk) measured along the surface. Rows run where
// the slope across them is at most the steep angle plus the split's overlap
// (10 degrees), so their closest spacing is cos(that) * sqrt(8 rk H)
// (`stepover`, what evenly spaced rows would take); waterlines run where it
// is at least the steep angle less the overlap, so their levels are at most
// sin(that) * sqrt(8 rk H) apart, farther where every wall between two
// levels is steeper (waterline.hpp, wall_spacing). The rows are spaced row by row by the slope
// across them below the steep angle (row_spacing.hpp): up to sqrt(8 rk H)
// apart over level ground. The scallop is the cusp between passes; the
// tolerance (merged points, arcs) comes on top of it, as in other CAM.
// Throws std::invalid_argument for a scallop on a flat cutter.
FinishSpacing finish_spacing(const ToolpathParams& p);

// The CL grid over the region at spacing.grid_step that the waterlines
// and the rows' spacing read the slope from.
cam::ClGrid ground_grid(const cam::ClEngine& engine, const cam::XYBounds& region, const FinishSpacing& spacing,
                   const cam::Checkpoint& checkpoint);

// Waterlines where the surface is steep, then the raster with its steep
// stretches bridged, into r.finish_pieces (and the waterline counts).
// `grid`: ground_grid's; `lattice`: the G-code's, as the raster's.
void add_waterlines(ToolpathProgram& r, const ToolpathParams& p, const cam::ClEngine& engine, const cam::ClGrid& grid,
                    const cam::XYLattice& lattice, const FinishSpacing& spacing, const cam::Checkpoint& checkpoint);

}  // namespace cncstream::jobs
