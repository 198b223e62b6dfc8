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

namespace cncstream::detail {

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

// Length of a closed loop.
double closed_length(const Polyline& loop);

// Douglas-Peucker on a closed loop (in XY): every dropped point within
// `tolerance` of the kept chords.
Polyline simplify_closed(const Polyline& loop, double tolerance);

}  // namespace cncstream::detail
