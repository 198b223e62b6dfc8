#include "cncstream/cam/level_band_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>

namespace cncstream::cam {

// Named: a unity build puts this file beside polyline_simplify.cpp.
namespace level_band {

constexpr double kEps = 1e-9;

// A straight move from the anchor `a` (a vertex already placed) over the
// points p[first..]: how far it can go with every point right of it and at
// most the tolerance away, and the directions (angles from `ref`, the
// direction to the first point) that reach there. The last point of the
// stretch is closed to its own position (the stretch's end is kept).
struct Reach {
  std::size_t last = 0;
  double lo = 0, hi = 0;  // angles from ref, counter-clockwise positive
};

struct Frame {
  double ax, ay;  // the anchor
  double rx, ry;  // unit reference direction
};

// `margin`: the move passes at least this far left of the points (and so
// at most tol - margin): room for moving its end onto the lattice.
Reach reach_level(const Polyline& p, std::size_t first, std::size_t end, const Frame& f, double tol, double margin) {
  Reach r{first, -std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  double along_before = 0;
  for (std::size_t k = first; k < end; ++k) {
    const double qx = p[k].x - f.ax, qy = p[k].y - f.ay;
    const double dist = std::hypot(qx, qy);
    const double along = qx * f.rx + qy * f.ry;
    // Points behind the anchor or going back along the move end it.
    if (k > first && (along <= along_before || along <= 0)) break;
    const double phi = std::atan2(f.rx * qy - f.ry * qx, along);  // angle of q from ref
    if (k > first && std::fabs(phi) > std::numbers::pi / 3) break;
    // Point k right of the line at angle t, by m to tol - m:
    // sin(phi - t) in [-(tol - m) / dist, -m / dist]  <=>  t in [phi + asin(m / dist), phi + asin((tol - m) / dist)].
    // The stretch's end is on the path (kept); points by the anchor keep no margin.
    const double m = k + 1 == end || dist <= 4 * margin ? 0.0 : margin;
    const double open = k + 1 == end || !(dist > 0) ? 0.0 : std::asin(std::min(1.0, (tol - m) / dist));
    const double shut = m > 0 ? std::asin(std::min(1.0, m / dist)) : 0.0;
    const double lo = std::max(r.lo, phi + shut), hi = std::min(r.hi, phi + open);
    if (k > first && lo > hi + kEps / std::max(dist, 1e-9)) break;
    r.last = k;
    r.lo = lo;
    r.hi = std::max(lo, hi);
    along_before = along;
  }
  return r;
}

// The vertex above point j on the line from the anchor at angle t: the
// foot of the perpendicular from p[j] (so p[j] is right of it by at most tol).
geometry::Vec3 vertex_on(const Frame& f, double t, const geometry::Vec3& pj) {
  const double c = std::cos(t), s = std::sin(t);
  const double dx = f.rx * c - f.ry * s, dy = f.rx * s + f.ry * c;
  const double along = (pj.x - f.ax) * dx + (pj.y - f.ay) * dy;
  return {f.ax + along * dx, f.ay + along * dy, pj.z};
}

Frame frame_at(const geometry::Vec3& a, const geometry::Vec3& toward) {
  const double dx = toward.x - a.x, dy = toward.y - a.y;
  const double len = std::hypot(dx, dy);
  return {a.x, a.y, len > 0 ? dx / len : 1.0, len > 0 ? dy / len : 0.0};
}

// Every point strictly between i and j right of the move a -> b and at most
// tol from it.
bool move_in_band(const Polyline& p, std::size_t i, std::size_t j, const geometry::Vec3& a, const geometry::Vec3& b, double tol) {
  const double len = std::hypot(b.x - a.x, b.y - a.y);
  if (!(len > 0)) return false;
  for (std::size_t k = i + 1; k < j; ++k) {
    const double side = ((b.x - a.x) * (p[k].y - a.y) - (b.y - a.y) * (p[k].x - a.x)) / len;
    const double along = ((p[k].x - a.x) * (b.x - a.x) + (p[k].y - a.y) * (b.y - a.y)) / len;
    if (side > kEps || side < -tol - kEps || along < 0 || along > len) return false;
  }
  return true;
}

// The vertex q for point j moved onto the lattice (the G-code's
// resolution, so the printed point is the checked one): the nearest of the
// four lattice points around it that keeps p[a+1..j] right of the move
// from `at` and within the tolerance; q itself if none does (rounding it
// then moves it by at most half a lattice step).
geometry::Vec3 on_lattice_in_band(const Polyline& p, std::size_t a, std::size_t j, const geometry::Vec3& at, const geometry::Vec3& q, double tol,
                        const std::optional<XYLattice>& lat) {
  if (!lat || !(lat->step > 0)) return q;
  const double s = lat->step;
  const double i0 = std::floor((q.x - lat->x0) / s), j0 = std::floor((q.y - lat->y0) / s);
  geometry::Vec3 cands[4];
  for (int c = 0; c < 4; ++c) cands[c] = {lat->x0 + (i0 + (c & 1)) * s, lat->y0 + (j0 + (c >> 1)) * s, q.z};
  std::sort(std::begin(cands), std::end(cands), [&](const geometry::Vec3& u, const geometry::Vec3& w) {
    return std::hypot(u.x - q.x, u.y - q.y) < std::hypot(w.x - q.x, w.y - q.y);
  });
  for (const geometry::Vec3& c : cands) {
    // p[j] itself: right of the move's line, and within the tolerance of the vertex.
    const double len = std::hypot(c.x - at.x, c.y - at.y);
    if (!(len > 0)) continue;
    const double side = ((c.x - at.x) * (p[j].y - at.y) - (c.y - at.y) * (p[j].x - at.x)) / len;
    if (side <= kEps && std::hypot(p[j].x - c.x, p[j].y - c.y) <= tol && move_in_band(p, a, j, at, c, tol)) return c;
  }
  return q;
}

// One level stretch p[b..e] (inclusive), its ends kept: appends the vertices after p[b].
void fit_stretch(const Polyline& p, std::size_t b, std::size_t e, double tol, const std::optional<XYLattice>& lat,
                 const LevelMoveCheck& clear, Polyline& out) {
  struct Placed {
    std::size_t index;
    geometry::Vec3 at;
  };
  std::vector<Placed> v{{b, p[b]}};
  std::size_t a = b;
  geometry::Vec3 at = p[b];
  // Half a lattice step's diagonal, where the band is wide enough to spare it.
  const double margin = lat && lat->step > 0 && tol > 4 * lat->step ? 0.75 * lat->step : 0.0;
  Frame f = frame_at(at, p[a + 1]);
  Reach r = reach_level(p, a + 1, e + 1, f, tol, margin);
  auto moved = [&](const geometry::Vec3& q, std::size_t k) { return q.x != p[k].x || q.y != p[k].y; };
  // Where no move out from the run is clear of the part (left of a point is
  // not free where the free side narrows to a slot), the run's own points
  // from the last vertex on, as they were.
  auto own_points_to = [&](std::size_t j) {
    if (moved(at, a)) v.push_back({a, p[a]});
    for (std::size_t k = a + 1; k <= j; ++k) v.push_back({k, p[k]});
    a = j;
    at = p[j];
  };
  while (r.last < e) {
    const std::size_t j = r.last;
    // Where in its window the vertex sits decides the next move's reach:
    // try a few, keep the farthest (the middle on ties).
    constexpr int kCandidates = 5;
    constexpr int kOrder[kCandidates] = {2, 1, 3, 0, 4};
    struct Candidate {
      geometry::Vec3 at;
      Reach next;
      Frame f;
    };
    Candidate cands[kCandidates];
    int n = 0;
    for (int c : kOrder) {
      const double t = r.lo + (r.hi - r.lo) * double(c) / double(kCandidates - 1);
      const geometry::Vec3 q = on_lattice_in_band(p, a, j, at, vertex_on(f, t, p[j]), tol, lat);
      if (r.hi - r.lo <= 0 && c != kOrder[0]) break;  // one slope: one candidate
      const Frame nf = frame_at(q, p[j + 1]);
      cands[n++] = {q, reach_level(p, j + 1, e + 1, nf, tol, margin), nf};
    }
    // The farthest-reaching candidate that is clear of the part (the middle
    // on ties): the geometry first, the exact check (the costly part) only
    // until one passes.
    std::stable_sort(cands, cands + n, [](const Candidate& u, const Candidate& w) { return u.next.last > w.next.last; });
    geometry::Vec3 best_at;
    Reach best{};
    Frame best_f{};
    bool have = false;
    for (int c = 0; c < n && !have; ++c) {
      const geometry::Vec3& q = cands[c].at;
      if (clear && (moved(q, j) || moved(at, a)) && !clear(at, q)) continue;
      best = cands[c].next, best_at = q, best_f = cands[c].f, have = true;
    }
    if (!have) {
      own_points_to(j);
      f = frame_at(at, p[a + 1]);
      r = reach_level(p, a + 1, e + 1, f, tol, margin);
      continue;
    }
    v.push_back({j, best_at});
    a = j;
    at = best_at;
    f = best_f;
    r = best;
  }
  if (clear && moved(at, a) && !clear(at, p[e])) own_points_to(e - 1);
  v.push_back({e, p[e]});
  // A vertex goes where the move from the one before it to the one after
  // stays in the band (the greedy's last move is often short).
  std::vector<Placed> kept{v.front()};
  for (std::size_t m = 1; m + 1 < v.size(); ++m) {
    const Placed &from = kept.back(), &to = v[m + 1];
    const bool merge = from.index < to.index && move_in_band(p, from.index, to.index, from.at, to.at, tol) &&
                       (!clear || clear(from.at, to.at));
    if (!merge) kept.push_back(v[m]);
  }
  kept.push_back(v.back());
  for (std::size_t m = 1; m < kept.size(); ++m) out.push_back(kept[m].at);
}

}  // namespace level_band

Polyline fit_level_run_in_band(const Polyline& run, double tolerance, const std::optional<XYLattice>& lattice,
                               const LevelMoveCheck& clear) {
  if (!(tolerance >= 0)) throw std::invalid_argument("fit_level_run_in_band: tolerance must not be negative");
  if (run.size() < 3) return run;
  Polyline out{run.front()};
  std::size_t b = 0;
  while (b + 1 < run.size()) {
    std::size_t e = b + 1;
    if (run[e].z != run[b].z) {
      out.push_back(run[e]);  // a lifted point: kept as it is
      b = e;
      continue;
    }
    while (e + 1 < run.size() && run[e + 1].z == run[b].z) ++e;
    bool distinct = true;
    for (std::size_t k = b; k < e && distinct; ++k)
      distinct = std::hypot(run[k + 1].x - run[k].x, run[k + 1].y - run[k].y) > 0;
    if (e == b + 1 || !distinct) {
      out.insert(out.end(), run.begin() + std::ptrdiff_t(b) + 1, run.begin() + std::ptrdiff_t(e) + 1);
    } else {
      level_band::fit_stretch(run, b, e, tolerance, lattice, clear, out);
    }
    b = e;
  }
  return out;
}

}  // namespace cncstream::cam
