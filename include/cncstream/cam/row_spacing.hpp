#pragma once
// Raster rows spaced by the ground between them. A ball or bull-nose pass
// leaves a cusp of about d^2 / (8 rk) between passes d apart along the
// surface; where the surface slopes across the rows at angle a, rows d apart
// in plan are d / cos(a) apart along it. So rows over level ground may be
// sqrt(8 rk H) apart, and only where the ground between two rows slopes
// across them must they close in. The slope comes from a CL grid: for these
// cutters the CL surface's normal is the part's at the contact.
#include <cstddef>
#include <vector>

#include "cncstream/cam/cl_grid.hpp"

namespace cncstream::cam {

class RowSpacing {
 public:
  // `grid`: the CL grid over the rows' region (at least 2 x 2 nodes).
  // along_x: rows run along X (the slope across them is dz/dy). widest: the
  // spacing over level ground. max_angle (radians, below pi/2): ground
  // steeper than this in any direction is left to another operation (the
  // waterlines) and does not count; slopes across the rows count up to it,
  // so no gap is narrower than cos(max_angle) * widest. Throws
  // std::invalid_argument for a smaller grid or a bad angle or width.
  RowSpacing(const ClGrid& grid, bool along_x, double widest, double max_angle);

  // The widest spacing of two rows at va < vb (across-row coordinates):
  // from the steepest slope across the rows at the grid lines between them
  // and one line beyond each (the slope between nodes is not sampled).
  double gap(double va, double vb) const;
  // The steepest slope across the rows counted on grid line k (radians).
  double line_angle(std::size_t k) const { return line_angle_[k]; }
  std::size_t lines() const { return line_angle_.size(); }
  double widest() const { return widest_; }

 private:
  double v0_ = 0, dv_ = 1;
  double widest_ = 0, max_angle_ = 0;
  std::vector<double> line_angle_;  // per grid line along the rows
};

}  // namespace cncstream::cam
