#include "cncstream/cam/cl_grid.hpp"

#include <cmath>
#include <stdexcept>

namespace cncstream::cam {

GridSpec GridSpec::covering(double x0, double y0, double x1, double y1, double dx, double dy) {
  if (!(dx > 0) || !(dy > 0)) throw std::invalid_argument("grid step must be positive");
  if (!(x1 >= x0) || !(y1 >= y0)) throw std::invalid_argument("grid bounds are empty (x1 < x0 or y1 < y0)");
  GridSpec g;
  g.x0 = x0;
  g.y0 = y0;
  g.dx = dx;
  g.dy = dy;
  g.nx = static_cast<std::size_t>(std::floor((x1 - x0) / dx * (1 + 1e-12) + 1e-9)) + 1;
  g.ny = static_cast<std::size_t>(std::floor((y1 - y0) / dy * (1 + 1e-12) + 1e-9)) + 1;
  return g;
}

}  // namespace cncstream::cam
