#pragma once
// How steep the CL surface is, per node of a CL grid: the angle of its
// gradient from the horizontal (central differences; one-sided at the
// border). For a ball or bull-nose cutter the CL surface's normal is the
// part's at the contact, so this is the part's slope under the cutter.
// Steep-and-shallow finishing splits the work by it.
#include <cstddef>
#include <vector>

#include "cncstream/cam/cl_grid.hpp"

namespace cncstream::cam {

class SlopeMap {
 public:
  // Throws std::invalid_argument for a grid of fewer than 2 x 2 nodes.
  explicit SlopeMap(const ClGrid& grid);

  const GridSpec& grid() const { return spec_; }
  // Radians, 0 (level) .. pi/2 (vertical).
  double at(std::size_t i, std::size_t j) const { return angle_[j * spec_.nx + i]; }
  // The steepest of the nodes of the cell holding (x, y) (clamped to the
  // grid): steep anywhere near counts, so a split by it errs on the side of
  // the steep operation.
  double max_near(double x, double y) const;
  // The gentlest of them (the shallow operation's side).
  double min_near(double x, double y) const;

 private:
  GridSpec spec_;
  std::vector<double> angle_;
};

}  // namespace cncstream::cam
