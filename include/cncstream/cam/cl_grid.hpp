#pragma once
// A regular XY grid of cutter-location heights (tool tip z).
// Node (i, j) is at (x0 + i*dx, y0 + j*dy); storage is row-major, x fastest.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace cncstream::cam {

struct GridSpec {
  double x0 = 0, y0 = 0;
  double dx = 1, dy = 1;
  std::size_t nx = 0, ny = 0;

  std::size_t size() const { return nx * ny; }
  double x(std::size_t i) const { return x0 + static_cast<double>(i) * dx; }
  double y(std::size_t j) const { return y0 + static_cast<double>(j) * dy; }
  double x1() const { return nx ? x(nx - 1) : x0; }
  double y1() const { return ny ? y(ny - 1) : y0; }

  // Nodes at x0 + i*step up to and including x1 (within step*1e-9).
  static GridSpec covering(double x0, double y0, double x1, double y1, double dx, double dy);
};

struct ClGrid {
  GridSpec spec;
  std::vector<double> z;      // tip heights, spec.size() values
  std::vector<std::uint8_t> on_floor;  // 1 where no facet was touched (z = floor)
  double floor = 0;

  double at(std::size_t i, std::size_t j) const { return z[j * spec.nx + i]; }
  double& at(std::size_t i, std::size_t j) { return z[j * spec.nx + i]; }
};

}  // namespace cncstream::cam
