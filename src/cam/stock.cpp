// Height-field stock: the per-move material removal loop.
#include "cncstream/cam/stock.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "swept_cutter.hpp"

namespace cncstream::cam {

namespace {

void check_cutter(const Cutter& c) {
  if (!(c.radius > 0) || !std::isfinite(c.radius))
    throw std::invalid_argument("cutter radius must be positive, got " + std::to_string(c.radius));
  if (!(c.corner_radius >= 0) || c.corner_radius > c.radius * (1 + 1e-12))
    throw std::invalid_argument("cutter corner radius " + std::to_string(c.corner_radius) +
                                " is outside 0..R = " + std::to_string(c.radius));
}

void check_point(const geometry::Vec3& p, const char* which) {
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
    throw std::invalid_argument(std::string("cut_segment: point ") + which + " is not finite");
}

struct Span {
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  void hull(double a, double b) {
    if (a > b) return;
    lo = std::min(lo, a);
    hi = std::max(hi, b);
  }
};

// x-range of the row y inside the capsule {p : dist(p, segment) <= R}. The
// capsule is convex, so the hull of its two end disks and its band is exact.
Span capsule_row(const detail::SweptCutter& sw, const geometry::Vec3& a, const geometry::Vec3& b, double y) {
  const double R = sw.radius();
  Span s;
  for (const geometry::Vec3* p : {&a, &b}) {
    const double dy = y - p->y;
    if (std::fabs(dy) <= R) {
      const double half = std::sqrt(R * R - dy * dy);
      s.hull(p->x - half, p->x + half);
    }
  }
  if (sw.vertical()) return s;
  // Band: 0 <= (x-ax)ux + (y-ay)uy <= L and |(y-ay)ux - (x-ax)uy| <= R.
  const double ux = sw.ux(), uy = sw.uy(), L = sw.length(), yy = y - a.y;
  double lo = -HUGE_VAL, hi = HUGE_VAL;
  auto constrain = [&](double coef, double cmin, double cmax) {  // cmin <= coef * X <= cmax, X = x - ax
    if (std::fabs(coef) < 1e-15) {
      if (cmin > 0 || cmax < 0) lo = HUGE_VAL, hi = -HUGE_VAL;
      return;
    }
    double p = cmin / coef, q = cmax / coef;
    if (p > q) std::swap(p, q);
    lo = std::max(lo, p);
    hi = std::min(hi, q);
  };
  constrain(ux, -yy * uy, L - yy * uy);
  constrain(-uy, -R - yy * ux, R - yy * ux);
  if (lo <= hi) s.hull(a.x + lo, a.x + hi);
  return s;
}

}  // namespace

HeightFieldStock::HeightFieldStock(const GridSpec& grid, double top) : grid_(grid), top_(top), rows_y0_(grid.y0) {
  if (grid.nx == 0 || grid.ny == 0) throw std::invalid_argument("stock grid is empty");
  if (!(grid.dx > 0) || !(grid.dy > 0)) throw std::invalid_argument("stock grid step must be positive");
  if (!std::isfinite(top)) throw std::invalid_argument("stock top must be finite");
  z_.assign(grid.size(), top);
}

HeightFieldStock::HeightFieldStock(const GridSpec& grid, double top, std::vector<double> heights)
    : HeightFieldStock(grid, top) {
  if (heights.size() != grid.size())
    throw std::invalid_argument("stock heights: " + std::to_string(heights.size()) + " values for a grid of " +
                                std::to_string(grid.size()) + " nodes");
  for (double& z : heights)
    if (!std::isfinite(z)) z = top;
  z_ = std::move(heights);
}

HeightFieldStock HeightFieldStock::band(const GridSpec& grid, std::size_t first_row, double top,
                                        std::vector<double> heights) {
  const std::size_t rows = grid.nx ? heights.size() / grid.nx : 0;
  if (rows == 0 || rows * grid.nx != heights.size() || first_row + rows > grid.ny)
    throw std::invalid_argument("stock band: " + std::to_string(heights.size()) + " heights from row " +
                                std::to_string(first_row) + " are not whole rows of a " + std::to_string(grid.nx) +
                                " x " + std::to_string(grid.ny) + " grid");
  GridSpec sub = grid;
  sub.y0 = grid.y(first_row);
  sub.ny = rows;
  HeightFieldStock s(sub, top, std::move(heights));
  s.rows_y0_ = grid.y0;
  s.first_row_ = first_row;
  return s;
}

double HeightFieldStock::cut_segment(const geometry::Vec3& a, const geometry::Vec3& b, const Cutter& cutter) {
  check_cutter(cutter);
  check_point(a, "a");
  check_point(b, "b");
  nodes_cut_ = 0;
  last_max_depth_ = 0;
  const detail::SweptCutter sw(a, b, cutter);
  const double R = sw.radius(), zfloor = sw.lowest_tip_z();
  const GridSpec& g = grid_;
  // Rows the capsule touches.
  const double ylo = std::min(a.y, b.y) - R, yhi = std::max(a.y, b.y) + R;
  const long jn = static_cast<long>(g.ny) - 1, in = static_cast<long>(g.nx) - 1;
  const long jb = static_cast<long>(first_row_);
  const long j0 = std::max(0L, static_cast<long>(std::ceil((ylo - rows_y0_) / g.dy - 1e-9)) - jb);
  const long j1 = std::min(jn, static_cast<long>(std::floor((yhi - rows_y0_) / g.dy + 1e-9)) - jb);
  double dropped = 0;
  for (long j = j0; j <= j1; ++j) {
    const double y = rows_y0_ + static_cast<double>(j + jb) * g.dy;
    const Span row = capsule_row(sw, a, b, y);
    if (row.lo > row.hi) continue;
    const long i0 = std::max(0L, static_cast<long>(std::ceil((row.lo - g.x0) / g.dx - 1e-9)));
    const long i1 = std::min(in, static_cast<long>(std::floor((row.hi - g.x0) / g.dx + 1e-9)));
    double* zrow = z_.data() + static_cast<std::size_t>(j) * g.nx;
    const double py = y - a.y;
    // Every node of this row is at least `ey` from the tip's path (its
    // distance in y alone), so the cutter's surface stays at or above
    // zfloor + h(ey) over all of them: nodes already that low are done.
    const double ey = std::max({0.0, std::min(a.y, b.y) - y, y - std::max(a.y, b.y)});
    const double zrow_floor = ey < R ? zfloor + sw.h(ey) : zfloor;
    for (long i = i0; i <= i1; ++i) {
      double& z = zrow[i];
      if (z <= zrow_floor) continue;  // the cutter cannot reach below this here
      const double px = g.x(static_cast<std::size_t>(i)) - a.x;
      double cut;
      if (sw.vertical()) {
        cut = sw.lowest_vertical(px * px + py * py);
      } else {
        const double along = px * sw.ux() + py * sw.uy(), perp = py * sw.ux() - px * sw.uy();
        cut = sw.lowest(along, perp * perp, z);
      }
      if (cut < z) {
        dropped += z - cut;
        last_max_depth_ = std::max(last_max_depth_, z - cut);
        z = cut;
        ++nodes_cut_;
      }
    }
  }
  const double volume = dropped * g.dx * g.dy;
  removed_ += volume;
  return volume;
}

double swept_lowest_height(const geometry::Vec3& a, const geometry::Vec3& b, const Cutter& cutter, double x, double y) {
  check_cutter(cutter);
  check_point(a, "a");
  check_point(b, "b");
  return detail::SweptCutter(a, b, cutter).lowest_at(x, y);
}

}  // namespace cncstream::cam
