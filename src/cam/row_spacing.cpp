#include "cncstream/cam/row_spacing.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace cncstream::cam {

RowSpacing::RowSpacing(const ClGrid& g, bool along_x, double widest, double max_angle)
    : v0_(along_x ? g.spec.y0 : g.spec.x0),
      dv_(along_x ? g.spec.dy : g.spec.dx),
      widest_(widest),
      max_angle_(max_angle) {
  const std::size_t nx = g.spec.nx, ny = g.spec.ny;
  if (nx < 2 || ny < 2 || g.z.size() != g.spec.size())
    throw std::invalid_argument("row spacing needs a CL grid of at least 2 x 2 nodes");
  if (!(widest > 0) || !(max_angle >= 0 && max_angle < std::numbers::pi / 2))
    throw std::invalid_argument("row spacing needs a positive width and an angle below 90 degrees");
  line_angle_.assign(along_x ? ny : nx, 0.0);
  const double tan_max = std::tan(max_angle);
  for (std::size_t j = 0; j < ny; ++j) {
    const std::size_t j0 = j == 0 ? 0 : j - 1, j1 = j + 1 == ny ? j : j + 1;
    for (std::size_t i = 0; i < nx; ++i) {
      const std::size_t i0 = i == 0 ? 0 : i - 1, i1 = i + 1 == nx ? i : i + 1;
      const double gx = (g.at(i1, j) - g.at(i0, j)) / (double(i1 - i0) * g.spec.dx);
      const double gy = (g.at(i, j1) - g.at(i, j0)) / (double(j1 - j0) * g.spec.dy);
      if (std::hypot(gx, gy) > tan_max) continue;  // steep: the waterlines' ground
      double& a = line_angle_[along_x ? j : i];
      a = std::max(a, std::atan(std::fabs(along_x ? gy : gx)));
    }
  }
}

double RowSpacing::gap(double va, double vb) const {
  const double n = double(line_angle_.size());
  const double lo = std::clamp(std::floor((std::min(va, vb) - v0_) / dv_) - 1, 0.0, n - 1);
  const double hi = std::clamp(std::ceil((std::max(va, vb) - v0_) / dv_) + 1, 0.0, n - 1);
  double a = 0;
  for (auto k = static_cast<std::size_t>(lo); k <= static_cast<std::size_t>(hi); ++k) a = std::max(a, line_angle_[k]);
  return std::cos(std::min(a, max_angle_)) * widest_;
}

}  // namespace cncstream::cam
