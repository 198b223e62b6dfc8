#include "cncstream/cam/slope_map.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cncstream::cam {

SlopeMap::SlopeMap(const ClGrid& g) : spec_(g.spec) {
  const std::size_t nx = spec_.nx, ny = spec_.ny;
  if (nx < 2 || ny < 2 || g.z.size() != spec_.size())
    throw std::invalid_argument("a slope map needs a CL grid of at least 2 x 2 nodes");
  angle_.resize(spec_.size());
  for (std::size_t j = 0; j < ny; ++j) {
    const std::size_t j0 = j == 0 ? 0 : j - 1, j1 = j + 1 == ny ? j : j + 1;
    for (std::size_t i = 0; i < nx; ++i) {
      const std::size_t i0 = i == 0 ? 0 : i - 1, i1 = i + 1 == nx ? i : i + 1;
      const double gx = (g.at(i1, j) - g.at(i0, j)) / (double(i1 - i0) * spec_.dx);
      const double gy = (g.at(i, j1) - g.at(i, j0)) / (double(j1 - j0) * spec_.dy);
      angle_[j * nx + i] = std::atan(std::hypot(gx, gy));
    }
  }
}

namespace {

template <class Pick>
double near_cell(const GridSpec& s, const std::vector<double>& a, double x, double y, Pick pick) {
  const double fx = std::clamp((x - s.x0) / s.dx, 0.0, double(s.nx - 1));
  const double fy = std::clamp((y - s.y0) / s.dy, 0.0, double(s.ny - 1));
  const auto i0 = std::min(static_cast<std::size_t>(fx), s.nx - 2);
  const auto j0 = std::min(static_cast<std::size_t>(fy), s.ny - 2);
  const std::size_t k = j0 * s.nx + i0;
  return pick(pick(a[k], a[k + 1]), pick(a[k + s.nx], a[k + s.nx + 1]));
}

}  // namespace

double SlopeMap::max_near(double x, double y) const {
  return near_cell(spec_, angle_, x, y, [](double p, double q) { return std::max(p, q); });
}

double SlopeMap::min_near(double x, double y) const {
  return near_cell(spec_, angle_, x, y, [](double p, double q) { return std::min(p, q); });
}

}  // namespace cncstream::cam
