#pragma once
// Material removal on a height-field stock: the machined top surface z(x, y)
// sampled on a regular grid. Every move lowers each node to the lowest point
// the cutter's surface reached above it (the exact swept shape of a flat,
// ball or bull-nose cutter along a straight segment). Used by the simulator
// and by cutter selection's scallop analysis; independent of the CL engine,
// so it can check it.
#include <cstddef>
#include <vector>

#include "cncstream/cam/cl_grid.hpp"
#include "cncstream/cam/cutter.hpp"
#include "cncstream/geometry/vec3.hpp"

namespace cncstream {

class HeightFieldStock {
 public:
  // Nodes of `grid` start at height `top`.
  HeightFieldStock(const GridSpec& grid, double top);

  const GridSpec& grid() const { return grid_; }
  double top() const { return top_; }
  const std::vector<double>& heights() const { return z_; }
  double at(std::size_t i, std::size_t j) const { return z_[j * grid_.nx + i]; }

  // Sweep the cutter's tip from a to b in a straight line (any direction,
  // including plunges and pure Z moves). Returns the volume removed (mm^3),
  // approximated by the node areas.
  double cut_segment(const Vec3& a, const Vec3& b, const Cutter& cutter);

  // Nodes whose height changed since the last call (for live views).
  std::size_t nodes_cut() const { return nodes_cut_; }

 private:
  GridSpec grid_;
  double top_;
  std::vector<double> z_;
  std::size_t nodes_cut_ = 0;
};

}  // namespace cncstream
