// Design comparison by vertical ray casting.
#include "cncstream/cam/deviation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace cncstream::cam {

DesignHeights design_heights(const geometry::Mesh& design, const GridSpec& g) {
  if (g.nx == 0 || g.ny == 0) throw std::invalid_argument("design heights: the grid is empty");
  if (!(g.dx > 0) || !(g.dy > 0)) throw std::invalid_argument("design heights: grid step must be positive");
  DesignHeights out;
  out.grid = g;
  out.z.assign(g.size(), -HUGE_VAL);
  // Every triangle hands its height to the nodes its XY shadow covers: the
  // same as casting every node's ray at every triangle, without the waste.
  for (std::size_t t = 0; t < design.size(); ++t) {
    const geometry::Vec3 a = design.corner(t, 0), b = design.corner(t, 1), c = design.corner(t, 2);
    const double area = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);  // twice the signed XY area
    const double span = std::max({std::fabs(b.x - a.x), std::fabs(c.x - a.x), std::fabs(b.y - a.y), std::fabs(c.y - a.y)});
    if (std::fabs(area) <= 1e-14 * span * span) continue;  // edge-on from above
    const double xlo = std::min({a.x, b.x, c.x}), xhi = std::max({a.x, b.x, c.x});
    const double ylo = std::min({a.y, b.y, c.y}), yhi = std::max({a.y, b.y, c.y});
    const long i0 = std::max(0L, static_cast<long>(std::ceil((xlo - g.x0) / g.dx - 1e-9)));
    const long i1 = std::min(static_cast<long>(g.nx) - 1, static_cast<long>(std::floor((xhi - g.x0) / g.dx + 1e-9)));
    const long j0 = std::max(0L, static_cast<long>(std::ceil((ylo - g.y0) / g.dy - 1e-9)));
    const long j1 = std::min(static_cast<long>(g.ny) - 1, static_cast<long>(std::floor((yhi - g.y0) / g.dy + 1e-9)));
    // Barycentric weights; a small tolerance makes shared edges count twice, never zero times.
    const double eps = 1e-12;
    for (long j = j0; j <= j1; ++j) {
      const double y = g.y(static_cast<std::size_t>(j));
      for (long i = i0; i <= i1; ++i) {
        const double x = g.x(static_cast<std::size_t>(i));
        const double wa = ((b.x - x) * (c.y - y) - (c.x - x) * (b.y - y)) / area;
        const double wb = ((c.x - x) * (a.y - y) - (a.x - x) * (c.y - y)) / area;
        const double wc = 1 - wa - wb;
        if (wa < -eps || wb < -eps || wc < -eps) continue;
        const double z = wa * a.z + wb * b.z + wc * c.z;
        double& dst = out.z[static_cast<std::size_t>(j) * g.nx + static_cast<std::size_t>(i)];
        dst = std::max(dst, z);
      }
    }
  }
  out.off_part.assign(g.size(), 0);
  for (std::size_t k = 0; k < g.size(); ++k) {
    if (out.z[k] == -HUGE_VAL) {
      out.z[k] = std::numeric_limits<double>::quiet_NaN();
      out.off_part[k] = 1;
    } else {
      ++out.on_part;
    }
  }
  return out;
}

DeviationResult compare_to_design(const HeightFieldStock& machined, const DesignHeights& design, double tolerance) {
  const GridSpec& g = machined.grid();
  const GridSpec& d = design.grid;
  if (g.nx != d.nx || g.ny != d.ny || g.x0 != d.x0 || g.y0 != d.y0 || g.dx != d.dx || g.dy != d.dy)
    throw std::invalid_argument("compare_to_design: the design heights were computed on a different grid");
  if (!(tolerance > 0) || !std::isfinite(tolerance))
    throw std::invalid_argument("compare_to_design: tolerance must be positive");
  DeviationResult r;
  r.grid = g;
  r.off_part = design.off_part;
  r.deviation.assign(g.size(), std::numeric_limits<double>::quiet_NaN());
  DeviationStats& s = r.stats;
  s.tolerance = tolerance;
  double sum = 0, sum_excess = 0, sum_excess2 = 0;
  std::vector<double> left;  // max(0, deviation) per on-part node
  left.reserve(design.on_part);
  auto at = [&](std::size_t k, double v) {
    return DeviationAt{v, g.x(k % g.nx), g.y(k / g.nx), k % g.nx, k / g.nx};
  };
  bool first = true;
  for (std::size_t k = 0; k < g.size(); ++k) {
    if (design.off_part[k]) {
      ++s.off_part;
      continue;
    }
    const double v = machined.heights()[k] - design.z[k];
    r.deviation[k] = v;
    ++s.on_part;
    sum += v;
    sum_excess += std::max(0.0, v);
    sum_excess2 += std::max(0.0, v) * std::max(0.0, v);
    left.push_back(std::max(0.0, v));
    s.gouged += v < -tolerance;
    s.excess += v > tolerance;
    if (v < 0 && (!s.has_gouge || v < s.largest_gouge.value)) {
      s.has_gouge = true;
      s.largest_gouge = at(k, v);
    }
    if (first || v > s.largest_excess.value) s.largest_excess = at(k, v);
    first = false;
  }
  if (s.on_part) {
    s.mean_deviation = sum / static_cast<double>(s.on_part);
    s.mean_excess = sum_excess / static_cast<double>(s.on_part);
    s.excess_rms = std::sqrt(sum_excess2 / static_cast<double>(s.on_part));
    // Nearest-rank percentiles, each by a selection pass (no full sort).
    auto percentile = [&](double p) {
      const auto rank = static_cast<std::size_t>(std::ceil(p * static_cast<double>(left.size()))) - 1;
      auto nth = left.begin() + static_cast<std::ptrdiff_t>(std::min(rank, left.size() - 1));
      std::nth_element(left.begin(), nth, left.end());
      return *nth;
    };
    s.excess_p50 = percentile(0.5);
    s.excess_p90 = percentile(0.9);
    s.excess_p99 = percentile(0.99);
  }
  return r;
}

std::string DeviationStats::summary() const {
  std::ostringstream o;
  o.setf(std::ios::fixed);
  o.precision(4);
  o << "nodes on part " << on_part << ", off part " << off_part << "\n";
  if (has_gouge)
    o << "largest gouge " << -largest_gouge.value << " mm below design at (" << largest_gouge.x << ", "
      << largest_gouge.y << ")\n";
  else
    o << "no gouge: the machined surface is nowhere below the design\n";
  if (on_part)
    o << "largest excess " << largest_excess.value << " mm at (" << largest_excess.x << ", " << largest_excess.y
      << "), mean excess " << mean_excess << " mm\n"
      << "material left (scallops): median " << excess_p50 << " mm, 90% " << excess_p90 << " mm, 99% " << excess_p99
      << " mm, RMS " << excess_rms << " mm\n";
  o << "beyond tolerance " << tolerance << " mm: " << gouged << " gouged, " << excess << " with excess\n";
  return o.str();
}

image::RgbImage render_deviation(const DeviationResult& r, const std::string& title, const std::string& subtitle,
                          int max_map_pixels) {
  const image::MapGrid mg{r.grid.nx, r.grid.ny, r.grid.dx, r.grid.dy, r.grid.x0, r.grid.y0};
  image::DeviationMapOptions o;
  o.title = title;
  o.subtitle = subtitle;
  o.tolerance = r.stats.tolerance;
  o.max_map_pixels = max_map_pixels;
  return image::render_deviation_map(mg, r.deviation, r.off_part, o);
}

void write_deviation_png(const std::filesystem::path& path, const DeviationResult& result, const std::string& title,
                         const std::string& subtitle) {
  image::write_png(path, render_deviation(result, title, subtitle));
}

}  // namespace cncstream::cam
