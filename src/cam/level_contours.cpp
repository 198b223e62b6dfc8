// Marching squares with refined crossings; see level_contours.hpp.
#include "cncstream/cam/level_contours.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace cncstream::cam {

namespace {

bool inside(double v, double level) { return v <= level; }  // NaN: outside

struct Tracer {
  const GridSpec& g;
  const std::vector<double>& v;
  double level;
  const PointQuery& exact;
  const ContourOptions& opt;
  std::size_t queries = 0;
  std::vector<geometry::Vec3> crossing;        // per edge id, valid where computed
  std::vector<std::uint8_t> done;

  // Edge ids: 2 * node for the edge to the +x neighbour, 2 * node + 1 to +y.
  std::size_t node(std::size_t i, std::size_t j) const { return j * g.nx + i; }

  geometry::Vec3 place(std::size_t edge) {
    if (done[edge]) return crossing[edge];
    const std::size_t n0 = edge / 2;
    const std::size_t i0 = n0 % g.nx, j0 = n0 / g.nx;
    const std::size_t n1 = (edge % 2 == 0) ? n0 + 1 : n0 + g.nx;
    const std::size_t i1 = n1 % g.nx, j1 = n1 / g.nx;
    // From the inside node p (t = 0) to the outside node q (t = 1).
    const bool in0 = inside(v[n0], level);
    const geometry::Vec3 p = in0 ? geometry::Vec3{g.x(i0), g.y(j0), level} : geometry::Vec3{g.x(i1), g.y(j1), level};
    const geometry::Vec3 q = in0 ? geometry::Vec3{g.x(i1), g.y(j1), level} : geometry::Vec3{g.x(i0), g.y(j0), level};
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
  double refine(const geometry::Vec3& p, const geometry::Vec3& q, double fa, double fb) {
    const double len = norm(q - p);
    double ta = 0, tb = 1;
    int side = 0, n = 0;
    bool bisect = false;
    if (opt.nested) {
      // Halvings fixed by the edge alone, so every level sees the same points.
      while ((tb - ta) * len > opt.xy_tolerance && n < opt.max_queries) {
        const double t = (ta + tb) / 2;
        const geometry::Vec3 at = p + (q - p) * t;
        (inside(exact(at.x, at.y), level) ? ta : tb) = t;
        ++n;
      }
      queries += static_cast<std::size_t>(n);
      return ta;
    }
    // fa_true: f at ta (Illinois scales fa and fb, not the ends' values).
    double fa_true = fa;
    while (fa_true < -opt.z_tolerance && (tb - ta) * len > opt.xy_tolerance && n < opt.max_queries) {
      const double width = tb - ta;
      double t = ta + width / 2;
      if (!bisect && std::isfinite(fb) && fb > fa) t = ta + width * (-fa) / (fb - fa);
      t = std::clamp(t, ta + width * 1e-3, tb - width * 1e-3);
      const geometry::Vec3 at = p + (q - p) * t;
      const double ft = exact(at.x, at.y) - level;
      ++n;
      if (ft <= 0) {  // inside (a NaN is outside)
        ta = t;
        fa = fa_true = ft;
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

double cross2(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }

// Corners of the region that chords cut off: between b and c of a, b, c, d
// where a-b and c-d turn left by a corner's angle and meet beyond b-c.
Polyline add_corners(const Polyline& pts, double level, const PointQuery& exact, const ContourOptions& opt,
                     double max_chord, std::size_t& queries, std::vector<geometry::Vec3>& corners) {
  const std::size_t n = pts.size();
  if (n < 4) return pts;
  const double min_sin = std::sin(opt.corner_angle_deg * 3.14159265358979323846 / 180);
  Polyline out;
  out.reserve(n + 8);
  for (std::size_t k = 0; k < n; ++k) {
    const geometry::Vec3& a = pts[(k + n - 1) % n];
    const geometry::Vec3& b = pts[k];
    const geometry::Vec3& c = pts[(k + 1) % n];
    const geometry::Vec3& d = pts[(k + 2) % n];
    out.push_back(b);
    const geometry::Vec3 u = b - a, v = d - c, w = c - b;
    const double lu = std::hypot(u.x, u.y), lv = std::hypot(v.x, v.y), lw = std::hypot(w.x, w.y);
    if (lu <= 0 || lv <= 0 || lw <= 0 || lw > max_chord) continue;
    const double turn = cross2(u.x, u.y, v.x, v.y);
    if (turn < min_sin * lu * lv) continue;  // not a left turn sharp enough
    // X = b + s u = c + t v.
    const double sb = cross2(c.x - b.x, c.y - b.y, v.x, v.y) / turn;
    if (!(sb > 0)) continue;
    const geometry::Vec3 x{b.x + sb * u.x, b.y + sb * u.y, level};
    if (cross2(w.x, w.y, x.x - b.x, x.y - b.y) >= 0) continue;  // not beyond the chord
    const geometry::Vec3 m = (b + c) * 0.5;
    if (std::hypot(x.x - m.x, x.y - m.y) > max_chord) continue;
    // The farthest point from m towards x that is inside (fixed halvings).
    double lo = 0, hi = 1;
    ++queries;
    if (!inside(exact(x.x, x.y), level)) {
      for (int it = 0; it < 12 && (hi - lo) * std::hypot(x.x - m.x, x.y - m.y) > opt.xy_tolerance; ++it) {
        const double t = (lo + hi) / 2;
        ++queries;
        (inside(exact(m.x + (x.x - m.x) * t, m.y + (x.y - m.y) * t), level) ? lo : hi) = t;
      }
    } else {
      lo = 1;
    }
    if (lo * std::hypot(x.x - m.x, x.y - m.y) <= opt.xy_tolerance) continue;
    out.push_back({m.x + (x.x - m.x) * lo, m.y + (x.y - m.y) * lo, level});
    corners.push_back(out.back());
  }
  return out;
}

}  // namespace

double signed_area2(const Polyline& loop) {
  double a = 0;
  for (std::size_t k = 0, n = loop.size(); k < n; ++k) {
    const geometry::Vec3& p = loop[k];
    const geometry::Vec3& q = loop[(k + 1) % n];
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

  Tracer tr{g, v, level, exact, opt, 0, std::vector<geometry::Vec3>(2 * g.size()), std::vector<std::uint8_t>(2 * g.size(), 0)};
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
  if (exact && opt.sharp_corners) {
    const double max_chord = std::hypot(g.dx, g.dy) * 1.01;
    for (auto& c : out.contours)
      if (c.closed) c.points = add_corners(c.points, level, exact, opt, max_chord, tr.queries, out.corner_points);
  }
  out.queries = tr.queries;
  out.crossings = static_cast<std::size_t>(std::count(tr.done.begin(), tr.done.end(), std::uint8_t{1}));
  return out;
}

LevelContours level_contours(const ClGrid& grid, double level, const PointQuery& exact, const ContourOptions& options) {
  return level_contours(grid.spec, grid.z, level, exact, options);
}

}  // namespace cncstream::cam
