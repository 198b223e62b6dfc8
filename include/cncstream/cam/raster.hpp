#pragma once
// Zig-zag raster finishing: rows `stepover` apart, the CL surface sampled
// along each row, every straight link checked against the exact CL surface,
// collinear points merged within a one-sided tolerance.
#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "cncstream/cam/checkpoint.hpp"
#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/polyline.hpp"
#include "cncstream/geometry/vec3.hpp"

namespace cncstream::cam {

enum class RasterDirection { X, Y };

struct XYBounds {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

// G-code prints coordinates with a fixed number of decimals. Beside a steep
// wall the CL surface rises almost vertically, so an XY rounded by half a
// micron there can put the tool tens of microns into the wall. With a lattice
// every XY of the path lies on origin + k * step (k integer) in each axis, so
// the printed coordinates are exactly where the CL was computed.
struct XYLattice {
  double step = 0.001;     // mm: 10^-decimals of the G-code
  double x0 = 0, y0 = 0;   // a lattice point: the work origin in model coordinates
  double z0 = 0;           // the work origin's height: printed Z values lie z0 + k * step
};

struct RasterOptions {
  double stepover = 0.4;        // distance between rows (upper bound; rows are spread evenly)
  double step = 0;              // sampling step along a row; 0 = min(stepover / 4, 0.1)
  int check_subdivisions = 2;   // each step is checked at step / check_subdivisions
  RasterDirection direction = RasterDirection::X;
  double tolerance = 0.002;     // merged chords stay within this above the CL surface
  std::optional<XYBounds> bounds;  // default: mesh XY box grown by the cutter radius
  // Without a lattice rows and samples are spread evenly over the bounds; with
  // one they are spaced by lattice multiples (the last interval may be
  // shorter) inside the bounds snapped inward to the lattice.
  std::optional<XYLattice> lattice;
  // Set: rows spaced by the ground between them (row_spacing.hpp):
  // row_gap(va, vb) is the widest two rows at va < vb (across the rows) may
  // be apart; `stepover` bounds it too. Each next row is the farthest the
  // gap allows, on the lattice; rows with equal spacing share a CL grid.
  std::function<double(double, double)> row_gap;
  // Keep the CL grid of the rows in RasterPath::grid (for analyses); evenly
  // spaced rows only (not with row_gap).
  bool keep_grid = false;
  // Set: where the rows' CL grids come from instead of the engine's exact
  // grid (the thesis's depth buffer, for comparing the two). Point queries
  // (a shorter last column, steep intervals) still ask the engine, and a
  // node below the exact surface is raised to it (one point query a node).
  std::function<ClGrid(const GridSpec&, const Checkpoint&)> grid_source;
};

struct RasterPath {
  std::vector<Polyline> rows;   // in cutting order, alternating direction
  std::vector<Polyline> links;  // links[k] joins rows[k] to rows[k+1] (checked against the CL)
  XYBounds bounds;
  double stepover = 0;          // actual distances used (the last row or sample may be closer)
  double stepover_min = 0;      // the narrowest between rows (= stepover for even rows; the last may be closer)
  double step = 0;
  std::size_t samples = 0;      // CL points computed (including check points)
  std::size_t points_before_merge = 0;
  std::size_t points_after_merge = 0;
  std::size_t refinement_queries = 0;  // point queries spent on steep intervals
  std::size_t raised_to_exact = 0;     // with a grid_source: its nodes below the exact surface
  // With RasterOptions::keep_grid: the exact CL grid the rows were sampled
  // from (rows at the stepover, the check step along them; a shorter last
  // row or column is not in it).
  ClGrid grid;
};

XYBounds default_bounds(const geometry::Mesh& mesh, const Cutter& cutter);

// Rows are refined as oneTBB tasks in the caller's task arena; the path does
// not depend on how they were scheduled. `checkpoint` is called as the CL grid
// and the rows are done (see checkpoint.hpp).
RasterPath build_raster(const ClEngine& engine, const XYBounds& bounds, const RasterOptions& options,
                        const Checkpoint& checkpoint = {});

}  // namespace cncstream::cam
