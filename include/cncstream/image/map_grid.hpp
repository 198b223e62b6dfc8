#pragma once
// Where a map's values sit: node (i, j) at (x0 + i*dx, y0 + j*dy), row-major
// with x fastest and j = 0 the southern (lowest y) row. Maps draw north
// (+y) up. Kept separate from cam's GridSpec so images do not depend on cam.
#include <cstddef>

namespace cncstream::image {

struct MapGrid {
  std::size_t nx = 0, ny = 0;
  double dx = 1, dy = 1;
  double x0 = 0, y0 = 0;

  std::size_t size() const { return nx * ny; }
};

}  // namespace cncstream::image
