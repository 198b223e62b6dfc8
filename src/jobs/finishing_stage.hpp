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
  double grid_step = 0;    // of the waterlines' CL grid
};

// With a scallop height H and a cutter of corner radius rk, a pass spacing
// d leaves cusps of d^2 / (8 rk) measured along the surface. Rows run where
// the slope across them is at most the steep angle plus the split's overlap
// (10 degrees), so their spacing is cos(that) * sqrt(8 rk H); waterlines run
// where it is at least the steep angle less the overlap, so their step is
// sin(that) * sqrt(8 rk H). The scallop is the cusp between passes; the
// tolerance (merged points, arcs) comes on top of it, as in other CAM.
// Throws std::invalid_argument for a scallop on a flat cutter.
FinishSpacing finish_spacing(const ToolpathParams& p);

// Waterlines where the surface is steep, then the raster with its steep
// stretches bridged, into r.finish_pieces (and the waterline counts).
// `lattice`: the G-code's, as the raster's.
void add_waterlines(ToolpathProgram& r, const ToolpathParams& p, const ClEngine& engine, const XYBounds& region,
                    const XYLattice& lattice, const FinishSpacing& spacing, const Checkpoint& checkpoint);

}  // namespace cncstream::jobs
