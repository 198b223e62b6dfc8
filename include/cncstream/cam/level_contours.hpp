#pragma once
// Level contours of a function sampled on a regular grid (marching squares):
// the boundary of the region {f(x, y) <= level}, traced with the region on
// the left (outer boundaries counter-clockwise, holes clockwise). Each
// crossing on a cell edge is placed by linear interpolation or, given the
// exact function, refined by point queries (safeguarded regula falsi) to a
// point inside the region: within `xy_tolerance` of the edge's crossing, or
// where f is within `z_tolerance` below the level. Used for Z-level roughing
// (f = the tip height of the CL surface) and waterlines.
//
// Saddle cells (two opposite corners inside) are resolved by the mean of the
// four corners: inside joins the inside corners. Between two crossings the
// contour is a straight chord; where the region is concave the chord can
// leave it by up to L^2 / (8 rho) (L: chord length, at most a cell diagonal;
// rho: the boundary's radius of curvature), so callers size the grid for
// their tolerance.
#include <cstddef>
#include <functional>
#include <vector>

#include "cncstream/cam/cl_grid.hpp"
#include "cncstream/cam/raster.hpp"

namespace cncstream::cam {

// The exact value of the sampled function at (x, y).
using PointQuery = std::function<double(double x, double y)>;

struct ContourOptions {
  double xy_tolerance = 1e-3;  // mm along the edge
  double z_tolerance = 1e-3;   // accept a point this close below the level (not when nested)
  int max_queries = 40;        // per crossing
  // Plain bisection, halving each edge until within xy_tolerance, instead of
  // regula falsi: slower, but the crossings of nested regions ({f <= l2}
  // inside {f <= l1} for l2 < l1) are nested on every edge, so the contour
  // of a lower level never pokes out of a higher one's (Z-level roughing
  // relies on it where walls are vertical).
  bool nested = false;
  // With the exact function: where the contour turns by more than
  // `corner_angle_deg` within one cell (a corner of the region cut off by a
  // chord), add the corner where the two neighbouring chords' lines meet,
  // or the farthest point towards it that the exact function puts inside.
  bool sharp_corners = true;
  double corner_angle_deg = 30;
};

struct LevelContour {
  Polyline points;     // z = the level; a closed loop does not repeat its first point
  bool closed = true;  // false: an open chain from the grid's border to its border
};

struct LevelContours {
  std::vector<LevelContour> contours;
  std::size_t queries = 0;    // point queries spent on refinement
  std::size_t crossings = 0;  // cell edges crossed
  std::vector<geometry::Vec3> corner_points;  // sharp corners added (points of the contours)
};

// `values`: grid.size() samples, node (i, j) at index j * nx + i; a NaN
// counts as outside. Open chains begin and end on border edges of the grid
// (the region continues beyond it). Throws std::invalid_argument if values
// do not match the grid or the grid has fewer than 2 x 2 nodes.
LevelContours level_contours(const GridSpec& grid, const std::vector<double>& values, double level,
                             const PointQuery& exact = {}, const ContourOptions& options = {});

// The contours of a CL grid at tip height `level`: where the tip can go down
// to `level` ({CL <= level}) on the left.
LevelContours level_contours(const ClGrid& grid, double level, const PointQuery& exact = {},
                             const ContourOptions& options = {});

// Twice the signed area of a closed loop (positive: counter-clockwise).
double signed_area2(const Polyline& loop);

}  // namespace cncstream::cam
