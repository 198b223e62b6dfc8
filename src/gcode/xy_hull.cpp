#include "cncstream/gcode/xy_hull.hpp"

#include <algorithm>
#include <cmath>

namespace cncstream::gcode {

namespace detail_xy_hull {

double turn(const XyPoint& o, const XyPoint& a, const XyPoint& b) {
  return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

// Distance of `p` from the line through a and b.
double chord_distance(const XyPoint& a, const XyPoint& b, const XyPoint& p) {
  const double len = std::hypot(b[0] - a[0], b[1] - a[1]);
  if (len == 0) return std::hypot(p[0] - a[0], p[1] - a[1]);
  return std::fabs(turn(a, b, p)) / len;
}

}  // namespace detail_xy_hull

std::vector<XyPoint> convex_hull(std::vector<XyPoint> pts) {
  using detail_xy_hull::turn;
  std::sort(pts.begin(), pts.end());
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  if (pts.size() < 3) return pts;
  // Andrew's monotone chain; `<= 0` drops collinear points.
  std::vector<XyPoint> h(2 * pts.size());
  std::size_t k = 0;
  for (const XyPoint& p : pts) {
    while (k >= 2 && turn(h[k - 2], h[k - 1], p) <= 0) --k;
    h[k++] = p;
  }
  for (std::size_t i = pts.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && turn(h[k - 2], h[k - 1], pts[i]) <= 0) --k;
    h[k++] = pts[i];
  }
  h.resize(k - 1);  // the last point is the first
  return h;
}

std::vector<XyPoint> simplify_hull(std::vector<XyPoint> h, double tolerance) {
  using detail_xy_hull::chord_distance;
  using detail_xy_hull::turn;
  const std::size_t n = h.size();
  if (n <= 3) return h;
  // Start at the sharpest corner, so a real corner is never cut.
  std::size_t start = 0;
  double sharpest = -1;
  for (std::size_t i = 0; i < n; ++i) {
    const XyPoint& a = h[(i + n - 1) % n];
    const XyPoint& b = h[(i + 1) % n];
    const double sine = turn(a, h[i], b) / (std::hypot(h[i][0] - a[0], h[i][1] - a[1]) *
                                             std::hypot(b[0] - h[i][0], b[1] - h[i][1]));
    if (sine > sharpest) sharpest = sine, start = i;
  }
  std::rotate(h.begin(), h.begin() + static_cast<std::ptrdiff_t>(start), h.end());
  // Greedy: each chord reaches as far as every ORIGINAL vertex it skips stays
  // within the tolerance of it, so the error never accumulates over passes.
  std::vector<XyPoint> kept{h[0]};
  for (std::size_t i = 0; i < n;) {
    std::size_t j = i + 1;
    for (; j < n; ++j) {  // may the chord from i reach j + 1 (n: the start)?
      const XyPoint& b = h[(j + 1) % n];
      bool within = true;
      for (std::size_t k = i + 1; k <= j && within; ++k) within = chord_distance(h[i], b, h[k]) <= tolerance;
      if (!within) break;
    }
    if (j >= n) break;
    kept.push_back(h[j]);
    i = j;
  }
  if (kept.size() < 3) return h;  // a sliver: keep what it is
  return kept;
}

void HullAccumulator::add(double x, double y) {
  points_.push_back({x, y});
  if (points_.size() >= limit_) points_ = convex_hull(std::move(points_));
}

}  // namespace cncstream::gcode
