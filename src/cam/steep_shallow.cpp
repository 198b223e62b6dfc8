#include "cncstream/cam/steep_shallow.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace cncstream::cam {

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
  // A merged row is a few long moves over level ground: judging only its
  // points would bridge a move from one wall's foot to the next over the
  // level ground between them. So each move is judged at points on it
  // half a slope-map cell apart (on its chord: no new height); these stay
  // out of the result unless a bridge starts or ends at one.
  const double spacing = 0.5 * std::min(slope.grid().dx, slope.grid().dy);
  for (const Polyline& p : pieces) {
    Polyline d;
    std::vector<std::uint8_t> real;
    for (std::size_t k = 0; k < p.size(); ++k) {
      if (k > 0) {
        const geometry::Vec3 a = p[k - 1], b = p[k];
        const auto n = static_cast<std::size_t>(std::ceil(std::hypot(b.x - a.x, b.y - a.y) / spacing));
        for (std::size_t m = 1; m < n; ++m) {
          d.push_back(a + (b - a) * (double(m) / double(n)));
          real.push_back(0);
        }
      }
      d.push_back(p[k]);
      real.push_back(1);
    }
    auto steep_at = [&](std::size_t k) { return slope.min_near(d[k].x, d[k].y) >= angle; };
    Polyline q;
    auto keep = [&](std::size_t k, bool always) {
      if (always || real[k]) q.push_back(d[k]);
    };
    std::size_t k = 0;
    while (k < d.size()) {
      if (k == 0 || !steep_at(k)) {
        keep(k++, false);
        continue;
      }
      // d[k..e) steep, d[k - 1] and d[e] (if any) gentle.
      std::size_t e = k;
      while (e < d.size() && steep_at(e)) ++e;
      if (e == d.size()) {
        // Steep to the end of the piece: nothing to bridge to.
        for (; k < e; ++k) keep(k, false);
        continue;
      }
      // The bridge starts at the last corner of the stretch (a link turning
      // into its row), so it runs along one row.
      std::size_t c = k - 1;
      while (c < e && !along_one_row(d, c, e)) ++c;
      if (e - c < 2) {
        // Too short to gain: cut as it is.
        for (; k < e; ++k) keep(k, false);
        continue;
      }
      for (; k < c; ++k) keep(k, false);
      // Its ends are cut to exactly (a point on a move is on its chord).
      if (q.empty() || !(q.back() == d[c])) q.push_back(d[c]);
      double top = -HUGE_VAL;
      for (std::size_t m = c; m <= e; ++m) top = std::max(top, d[m].z);
      const geometry::Vec3& a = d[c];
      const geometry::Vec3& b = d[e];
      if (top > a.z) q.push_back({a.x, a.y, top});
      if (top > b.z) q.push_back({b.x, b.y, top});
      ++out.bridges;
      for (std::size_t m = c + 1; m < e; ++m) out.points_skipped += real[m];
      keep(e, true);
      k = e + 1;
    }
    out.pieces.push_back(std::move(q));
  }
  return out;
}

}  // namespace cncstream::cam
