// Marching squares with refined crossings; see level_contours.hpp.
#include "cncstream/cam/level_contours.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace cncstream {

namespace {

bool inside(double v, double level) { return v <= level; }  // NaN: outside

struct Tracer {
  const GridSpec& g;
  const std::vector<double>& v;
  double level;
  const PointQuery& exact;
  const ContourOptions& opt;
  std::size_t queries = 0;
  std::vector<Vec3> crossing;        // per edge id, valid where computed
  std::vector<std::uint8_t> done;

  // Edge ids: 2 * node for the edge to the +x neighbour, 2 * node + 1 to +y.
  std::size_t node(std::size_t i, std::size_t j) const { return j * g.nx + i; }

  Vec3 place(std::size_t edge) {
    if (done[edge]) return crossing[edge];
    const std::size_t n0 = edge / 2;
    const std::size_t i0 = n0 % g.nx, j0 = n0 / g.nx;
    const std::size_t n1 = (edge % 2 == 0) ? n0 + 1 : n0 + g.nx;
    const std::size_t i1 = n1 % g.nx, j1 = n1 / g.nx;
    // From the inside node p (t = 0) to the outside node q (t = 1).
    const bool in0 = inside(v[n0], level);
    const Vec3 p = in0 ? Vec3{g.x(i0), g.y(j0), level} : Vec3{g.x(i1), g.y(j1), level};
    const Vec3 q = in0 ? Vec3{g.x(i1), g.y(j1), level} : Vec3{g.x(i0), g.y(j0), level};
    double fa = (in0 ? v[n0] : v[n1]) - level, fb = (in0 ? v[n1] : v[n0]) - level;
    double t;
    if (!exact) {
      t = std::isfinite(fb) && fb > fa ? -fa / (fb - fa) : 0.5;
    } else {
      t = refine(p, q, fa, fb);
    }
    crossing[edge] = p + (q - p) * t;
    done[edge] = 1;
    return crossing[edge];
  }

  // Safeguarded regula falsi (Illinois) on [0, 1], keeping an inside end.
  double refine(const Vec3& p, const Vec3& q, double fa, double fb) {
    const double len = norm(q - p);
    double ta = 0, tb = 1;
    int side = 0, n = 0;
    bool bisect = false;
    if (opt.nested) {
      // Halvings fixed by the edge alone, so every level sees the same points.
      while ((tb - ta) * len > opt.xy_tolerance && n < opt.max_queries) {
        const double t = (ta + tb) / 2;
        const Vec3 at = p + (q - p) * t;
        (inside(exact(at.x, at.y), level) ? ta : tb) = t;
        ++n;
      }
      queries += static_cast<std::size_t>(n);
      return ta;
    }
    while (fa < -opt.z_tolerance && (tb - ta) * len > opt.xy_tolerance && n < opt.max_queries) {
      const double width = tb - ta;
      double t = ta + width / 2;
      if (!bisect && std::isfinite(fb) && fb > fa) t = ta + width * (-fa) / (fb - fa);
      t = std::clamp(t, ta + width * 1e-3, tb - width * 1e-3);
      const Vec3 at = p + (q - p) * t;
      const double ft = exact(at.x, at.y) - level;
      ++n;
      if (inside(ft + level, level)) {
        ta = t;
        fa = ft;
        if (side == -1 && std::isfinite(fb)) fb /= 2;
        side = -1;
      } else {
        tb = t;
        fb = ft;
        if (side == 1) fa /= 2;
        side = 1;
      }
      bisect = tb - ta > width / 2;  // a slow step: halve the bracket next
    }
    queries += static_cast<std::size_t>(n);
    return ta;
  }
};

}  // namespace

double signed_area2(const Polyline& loop) {
  double a = 0;
  for (std::size_t k = 0, n = loop.size(); k < n; ++k) {
    const Vec3& p = loop[k];
    const Vec3& q = loop[(k + 1) % n];
    a += p.x * q.y - q.x * p.y;
  }
  return a;
}

LevelContours level_contours(const GridSpec& g, const std::vector<double>& v, double level, const PointQuery& exact,
                             const ContourOptions& opt) {
  if (v.size() != g.size())
    throw std::invalid_argument("level contours: " + std::to_string(v.size()) + " values for a grid of " +
                                std::to_string(g.size()) + " nodes");
  if (g.nx < 2 || g.ny < 2) throw std::invalid_argument("level contours need a grid of at least 2 x 2 nodes");
  if (!std::isfinite(level)) throw std::invalid_argument("level contours: the level must be finite");

  Tracer tr{g, v, level, exact, opt, 0, std::vector<Vec3>(2 * g.size()), std::vector<std::uint8_t>(2 * g.size(), 0)};
  struct Segment {
    std::size_t from, to;  // edge ids
  };
  std::vector<Segment> segs;
  constexpr std::size_t none = static_cast<std::size_t>(-1);
  std::vector<std::size_t> starts_at(2 * g.size(), none);
  std::vector<std::uint8_t> ends_at(2 * g.size(), 0);

  for (std::size_t j = 0; j + 1 < g.ny; ++j)
    for (std::size_t i = 0; i + 1 < g.nx; ++i) {
      // Corners counter-clockwise a, b, c, d and the edges a-b, b-c, c-d, d-a.
      const std::size_t a = tr.node(i, j), b = a + 1, c = b + g.nx, d = a + g.nx;
      const std::size_t corner[4] = {a, b, c, d};
      const std::size_t edge[4] = {2 * a, 2 * b + 1, 2 * d, 2 * a + 1};
      bool in[4];
      int count = 0;
      for (int k = 0; k < 4; ++k) count += (in[k] = inside(v[corner[k]], level)) ? 1 : 0;
      if (count == 0 || count == 4) continue;
      bool leaving[4], entering[4];
      for (int k = 0; k < 4; ++k) {
        leaving[k] = in[k] && !in[(k + 1) % 4];
        entering[k] = !in[k] && in[(k + 1) % 4];
      }
      const bool saddle = count == 2 && in[0] == in[2];
      bool centre_in = true;
      if (saddle) {
        double s = 0;
        for (std::size_t n : corner) s += v[n];
        centre_in = inside(s / 4, level);
      }
      for (int k = 0; k < 4; ++k) {
        if (!leaving[k]) continue;
        // The partner crossing: next (centre inside) or previous entering edge.
        int m = k;
        for (int step = 1; step < 4; ++step) {
          const int cand = centre_in ? (k + step) % 4 : (k + 4 - step) % 4;
          if (entering[cand]) {
            m = cand;
            break;
          }
        }
        starts_at[edge[k]] = segs.size();
        ends_at[edge[m]] = 1;
        segs.push_back({edge[k], edge[m]});
      }
    }

  LevelContours out;
  std::vector<std::uint8_t> used(segs.size(), 0);
  auto trace = [&](std::size_t s0, bool closed) {
    LevelContour c;
    c.closed = closed;
    c.points.push_back(tr.place(segs[s0].from));
    std::size_t s = s0;
    while (s != none && !used[s]) {
      used[s] = 1;
      const std::size_t e = segs[s].to;
      s = starts_at[e];
      if (closed && s == s0) break;
      c.points.push_back(tr.place(e));
    }
    out.contours.push_back(std::move(c));
  };
  // Open chains first: they start on a border edge nothing ends at.
  for (std::size_t s = 0; s < segs.size(); ++s)
    if (!used[s] && !ends_at[segs[s].from]) trace(s, false);
  for (std::size_t s = 0; s < segs.size(); ++s)
    if (!used[s]) trace(s, true);
  out.queries = tr.queries;
  out.crossings = static_cast<std::size_t>(std::count(tr.done.begin(), tr.done.end(), std::uint8_t{1}));
  return out;
}

LevelContours level_contours(const ClGrid& grid, double level, const PointQuery& exact, const ContourOptions& options) {
  return level_contours(grid.spec, grid.z, level, exact, options);
}

}  // namespace cncstream
