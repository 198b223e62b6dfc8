#pragma once
// Scallops of a raster from an exact cut simulation: residual = machined -
// design at every node of the simulation grid, and for every pair of
// adjacent passes and every column along them the largest residual strictly
// between the two passes (the cusp left there). Given the cutter's reach
// limit (reach.hpp), the residual is split: material the cutter cannot reach
// at any stepover is "unreachable", the rest is scallop.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "cncstream/cam/cl_grid.hpp"
#include "cncstream/cam/deviation.hpp"

namespace cncstream::cam {

struct ScallopStats {
  double max = 0, min = 0, mean = 0;  // over pass pairs x columns with material between them
  std::size_t samples = 0;
};

// Material left where the cutter cannot reach (over on-part nodes).
struct UnreachableStats {
  double max = 0, mean = 0;
  double share = 0;                 // of on-part nodes holding more than kUnreachableMin
  double max_x = 0, max_y = 0;      // where the largest is
  bool computed = false;            // false: no reach limit was given
};
// Below this an "unreachable" height is the reach lattice's own scallop.
inline constexpr double kUnreachableMin = 0.01;

// The part of a node's residual (machined - design) above the cutter's reach
// limit; 0 where the limit was not computed (NaN). The raster may cut a hair
// below the lattice's reach between its nodes: the reach counts only up to
// the machined surface.
inline double unreachable_part(double machined, double design, double reach) {
  return std::isfinite(reach) ? std::max(0.0, std::min(reach, machined) - design) : 0.0;
}

struct ScallopMap {
  GridSpec grid;
  std::vector<double> residual;      // machined - design per node; NaN off part
  std::vector<double> unreachable;   // the part of residual above the reach limit; 0 without one, NaN off part
  std::size_t columns = 0;           // nodes along the passes
  std::vector<double> pair_scallop;  // (passes - 1) x columns, pass pair major; NaN where no on-part node lies between
  std::vector<double> strip;         // per node: the scallop of the pass pair it lies in (a pass counts with the pair above it)
  ScallopStats stats;                // of pair_scallop: scallop only, when a reach limit was given
  UnreachableStats unreachable_stats;
};

// rows: the passes' positions across them (y for passes along x, else x),
// increasing. reach: per node the cutter's reach limit (NaN where not
// computed: the residual there counts as scallop), or null. Throws
// std::invalid_argument on mismatched sizes.
ScallopMap scallops_from_cut(const GridSpec& grid, const std::vector<double>& machined, const DesignHeights& design,
                             const std::vector<double>& rows, bool passes_along_x,
                             const std::vector<double>* reach = nullptr);

ScallopStats scallop_stats(const std::vector<double>& values);

}  // namespace cncstream::cam
