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

namespace cncstream::cam {

class HeightFieldStock {
 public:
  // Nodes of `grid` start at height `top`. Throws std::invalid_argument for
  // an empty grid, a non-positive step or a non-finite top.
  HeightFieldStock(const GridSpec& grid, double top);
  // A stock already machined to `heights` (grid.size() values; a machined
  // result read back from a file). Non-finite values are taken as `top`.
  HeightFieldStock(const GridSpec& grid, double top, std::vector<double> heights);
  // Rows [first_row, first_row + heights.size() / grid.nx) of a stock over
  // `grid`, at `heights`. Its nodes keep the whole grid's coordinates
  // (grid.y0 + j * grid.dy, not restarted from the band's first row), so
  // bands cut apart equal, bit for bit, the same rows of one stock over the
  // whole grid; grid() describes the band. Throws as the constructors above
  // and for heights that are not whole rows inside the grid.
  static HeightFieldStock band(const GridSpec& grid, std::size_t first_row, double top, std::vector<double> heights);

  const GridSpec& grid() const { return grid_; }
  double top() const { return top_; }
  const std::vector<double>& heights() const { return z_; }
  double at(std::size_t i, std::size_t j) const { return z_[j * grid_.nx + i]; }

  // Sweep the cutter's tip from a to b in a straight line (any direction,
  // including plunges and pure Z moves). Only nodes within the cutter radius
  // of the path's XY footprint are visited. Returns the volume removed
  // (mm^3): the sum of height drops times the node area dx*dy. Throws
  // std::invalid_argument for non-finite points or a bad cutter.
  double cut_segment(const geometry::Vec3& a, const geometry::Vec3& b, const Cutter& cutter);

  // Nodes whose height changed in the last cut_segment call (for live views).
  std::size_t nodes_cut() const { return nodes_cut_; }
  // The largest height drop of a node in the last cut_segment call (mm; 0 if
  // nothing was cut): the depth the move took off, for checks of a path's
  // depth of cut per move.
  double last_max_depth() const { return last_max_depth_; }

  // Total volume removed since construction (mm^3).
  double removed_volume() const { return removed_; }

 private:
  GridSpec grid_;
  double top_;
  // Node rows are at rows_y0_ + (first_row_ + j) * grid_.dy: the whole grid's
  // coordinates for a band, grid_'s own otherwise.
  double rows_y0_ = 0;
  std::size_t first_row_ = 0;
  std::vector<double> z_;
  std::size_t nodes_cut_ = 0;
  double last_max_depth_ = 0;
  double removed_ = 0;
};

// The lowest height the cutter's surface reaches above (x, y) while its tip
// moves straight from a to b; +infinity if it never passes over (x, y). This
// is the per-node rule cut_segment applies, exposed for checks.
double swept_lowest_height(const geometry::Vec3& a, const geometry::Vec3& b, const Cutter& cutter, double x, double y);

}  // namespace cncstream::cam
