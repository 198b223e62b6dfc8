#pragma once
// One level of Z-level roughing: the loops that clear the tip region (its
// boundary from the exact CL, and iso-lines of its distance transform every
// stepover inside), each tagged with the connected part of the region it
// lies in. Internal to the roughing.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "cncstream/cam/cl_grid.hpp"
#include "cncstream/cam/level_contours.hpp"

namespace cncstream::cam::detail {

struct RegionLoop {
  Polyline points;        // closed (first point not repeated), region on the left
  int offset = 0;         // 0: the region's boundary; k: k stepovers inside
  std::size_t component = 0;
  double length = 0;
};

struct LevelRegion {
  std::vector<RegionLoop> loops;
  std::size_t components = 0;
  std::size_t queries = 0;
  std::vector<std::uint8_t> inside;  // per node: 1 where phi <= 0
  std::vector<geometry::Vec3> corners;         // boundary points added at sharp corners
};

struct RegionInput {
  const GridSpec* grid = nullptr;
  const std::vector<double>* phi = nullptr;  // <= 0 inside the tip region, per node
  const PointQuery* exact = nullptr;         // phi at any point
  double stepover = 1;
  double boundary_tolerance = 0.01;  // for refining and simplifying the boundary
  double inner_tolerance = 0.1;      // for simplifying the inner loops
};

LevelRegion level_region(const RegionInput& in);

// Drops from the boundary loops of `region` the sharp corners that lie
// outside `above` (the boundary loops of the level above, if any), then
// drops exactly collinear points. Crossings on the grid's edges are nested
// level to level (nested bisection), corners are not: one poking out of the
// level above's loops would reach material no loop of that level cleared.
// Only exactly collinear points go: a boundary simplified within a tolerance
// could poke out of the level above's by it, the cutter there meeting a
// sliver of uncut material the whole height of the levels above. Returns
// the number of corners dropped.
std::size_t settle_boundary(LevelRegion& region, const std::vector<Polyline>* above);

// Whether p is inside closed loops with the region on their left (winding
// number), or within 1e-9 of one.
bool inside_loops(const geometry::Vec3& p, const std::vector<Polyline>& loops);

// Length of a closed loop.
double closed_length(const Polyline& loop);

// Douglas-Peucker on a closed loop (in XY): every dropped point within
// `tolerance` of the kept chords.
Polyline simplify_closed(const Polyline& loop, double tolerance);

}  // namespace cncstream::cam::detail
