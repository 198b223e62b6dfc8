#include "cncstream/cam/steep_shallow.hpp"

#include <algorithm>
#include <cmath>

namespace cncstream {

namespace {

// All of p[a..b] on one line of constant x or constant y.
bool along_one_row(const Polyline& p, std::size_t a, std::size_t b) {
  bool same_x = true, same_y = true;
  for (std::size_t k = a + 1; k <= b; ++k) {
    same_x = same_x && std::fabs(p[k].x - p[a].x) < 1e-9;
    same_y = same_y && std::fabs(p[k].y - p[a].y) < 1e-9;
  }
  return same_x || same_y;
}

}  // namespace

SteepSkip skip_steep(const std::vector<Polyline>& pieces, const SlopeMap& slope, double angle) {
  SteepSkip out;
  for (const Polyline& p : pieces) {
    Polyline q;
    std::size_t k = 0;
    while (k < p.size()) {
      const bool steep = k > 0 && slope.min_near(p[k].x, p[k].y) >= angle;
      if (!steep) {
        q.push_back(p[k++]);
        continue;
      }
      // p[k..e) steep, p[k - 1] and p[e] (if any) gentle.
      std::size_t e = k;
      while (e < p.size() && slope.min_near(p[e].x, p[e].y) >= angle) ++e;
      if (e == p.size()) {
        // Steep to the end of the piece: nothing to bridge to.
        for (; k < e; ++k) q.push_back(p[k]);
        continue;
      }
      // The bridge starts at the last corner of the stretch (a link turning
      // into its row), so it runs along one row.
      std::size_t c = k - 1;
      while (c < e && !along_one_row(p, c, e)) ++c;
      if (e - c < 2) {
        // Too short to gain: cut as it is.
        for (; k < e; ++k) q.push_back(p[k]);
        continue;
      }
      for (; k <= c; ++k) q.push_back(p[k]);
      double top = -HUGE_VAL;
      for (std::size_t m = c; m <= e; ++m) top = std::max(top, p[m].z);
      const Vec3& a = p[c];
      const Vec3& b = p[e];
      if (top > a.z) q.push_back({a.x, a.y, top});
      if (top > b.z) q.push_back({b.x, b.y, top});
      ++out.bridges;
      out.points_skipped += e - c - 1;
      k = e;
    }
    out.pieces.push_back(std::move(q));
  }
  return out;
}

}  // namespace cncstream
