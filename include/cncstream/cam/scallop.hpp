#pragma once
// Scallops of a raster from an exact cut simulation: residual = machined -
// design at every node of the simulation grid, and for every pair of
// adjacent passes and every column along them the largest residual strictly
// between the two passes (the cusp left there).
#include <cstddef>
#include <vector>

#include "cncstream/cam/cl_grid.hpp"
#include "cncstream/cam/deviation.hpp"

namespace cncstream {

struct ScallopStats {
  double max = 0, min = 0, mean = 0;  // over pass pairs x columns with material between them
  std::size_t samples = 0;
};

struct ScallopMap {
  GridSpec grid;
  std::vector<double> residual;      // machined - design per node; NaN off part
  std::size_t columns = 0;           // nodes along the passes
  std::vector<double> pair_scallop;  // (passes - 1) x columns, pass pair major; NaN where no on-part node lies between
  std::vector<double> strip;         // per node: the scallop of the pass pair it lies in (a pass counts with the pair above it)
  ScallopStats stats;
};

// rows: the passes' positions across them (y for passes along x, else x),
// increasing. Throws std::invalid_argument on mismatched sizes.
ScallopMap scallops_from_cut(const GridSpec& grid, const std::vector<double>& machined, const DesignHeights& design,
                             const std::vector<double>& rows, bool passes_along_x);

ScallopStats scallop_stats(const std::vector<double>& values);

}  // namespace cncstream
