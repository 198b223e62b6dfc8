#include "cncstream/gcode/arc_fit.hpp"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

#include "cncstream/gcode/arc_segments.hpp"

namespace cncstream {

namespace {

using gcode::Plane;

using gcode::axes_of;
using gcode::PlaneAxes;

struct P2 {
  double a = 0, b = 0;
};
P2 operator-(P2 p, P2 q) { return {p.a - q.a, p.b - q.b}; }
double dot2(P2 p, P2 q) { return p.a * q.a + p.b * q.b; }
double cross2(P2 p, P2 q) { return p.a * q.b - p.b * q.a; }
double len2(P2 p) { return std::hypot(p.a, p.b); }

// Angle from u to v turning counter-clockwise, in [0, 2 pi).
double ccw_angle(P2 u, P2 v) {
  double t = std::atan2(cross2(u, v), dot2(u, v));
  if (t < 0) t += 2 * std::numbers::pi;
  return t;
}

// Distance from c to the segment p-q.
double distance_to_segment(P2 c, P2 p, P2 q) {
  const P2 d = q - p;
  const double l2 = dot2(d, d);
  double t = l2 > 0 ? dot2(c - p, d) / l2 : 0;
  t = std::clamp(t, 0.0, 1.0);
  return len2(c - P2{p.a + t * d.a, p.b + t * d.b});
}

// The chords the controller cuts an arc with, as GRBL's mc_arc makes them:
// floor(length / nominal chord) of them (one at least), their ends on the
// circle at equal angles. The controller counts in float: where the quotient
// is within its rounding of a whole number, both counts are allowed for.
class ChordModel {
 public:
  ChordModel(double r, double sweep, double arc_tolerance) : r_(r) {
    if (!(arc_tolerance > 0) || !(arc_tolerance < 2 * r)) return;  // an exact arc
    const double x = 0.5 * sweep * r / std::sqrt(arc_tolerance * (2 * r - arc_tolerance));
    for (int k = 0; k < 2; ++k) {
      const double c = std::clamp(std::floor(x * (k == 0 ? 1 - 1e-5 : 1 + 1e-5)), 1.0, 65535.0);
      deltas_[k] = sweep / c;
      counts_[k] = c;
      cos_half_[k] = std::cos(0.5 * deltas_[k]);
    }
    models_ = counts_[0] == counts_[1] ? 1 : 2;
  }
  // The smallest distance from the centre of any chord (at its middle).
  double deepest() const {
    double lowest = r_;
    for (int k = 0; k < models_; ++k) lowest = std::min(lowest, r_ * cos_half_[k]);
    return lowest;
  }
  // Smallest distance from the centre, over the chord counts, of the chord
  // path at angle phi from the start (r itself at a chord's end).
  double lowest_radius(double phi) const {
    double lowest = r_;
    for (int k = 0; k < models_; ++k) {
      const double d = deltas_[k];
      const double idx = std::clamp(std::floor(phi / d), 0.0, counts_[k] - 1);
      const double off = phi - (idx + 0.5) * d;
      lowest = std::min(lowest, r_ * cos_half_[k] / std::cos(off));
    }
    return lowest;
  }

 private:
  double r_;
  int models_ = 0;  // 0: an exact arc
  double deltas_[2] = {0, 0};
  double counts_[2] = {1, 1};
  double cos_half_[2] = {1, 1};
};

class Fitter {
 public:
  Fitter(const std::vector<geometry::Vec3>& pts, const ArcFitOptions& o) : pts_(pts), o_(o) {}

  // The arc from point i to point j, if one fits.
  std::optional<FittedMove> arc(std::size_t i, std::size_t j) const {
    const std::optional<Plane> plane = plane_of(i, j);
    if (!plane) return std::nullopt;
    const PlaneAxes ax = axes_of(*plane);
    // A run over material below: the plane must be upright (Z one of its
    // axes), unless it is a level run beside material on its right.
    const bool level_sided = o_.material_right && *plane == Plane::XY;
    if (o_.material_below && *plane == Plane::XY && !level_sided) return std::nullopt;
    auto at = [&](std::size_t k) { return P2{component(pts_[k], ax.first), component(pts_[k], ax.second)}; };
    const P2 A = at(i), B = at(j);
    const double d = len2(B - A);
    if (!(d > 1e-6)) return std::nullopt;
    const P2 M{0.5 * (A.a + B.a), 0.5 * (A.b + B.b)};
    const P2 u{(B.a - A.a) / d, (B.b - A.b) / d};
    const P2 n{-u.b, u.a};  // centres lie at M + t n
    // The side the points bulge to: the farthest from the chord decides.
    // One pass: the farthest point, and the sums of the least-squares centre below.
    std::size_t far = i + 1;
    double bulge = 0, sum_ab = 0, sum_bb = 0;
    for (std::size_t k = i + 1; k < j; ++k) {
      const P2 q = at(k) - M;
      const double side_k = dot2(q, n);
      if (std::fabs(side_k) > std::fabs(bulge)) {
        bulge = side_k;
        far = k;
      }
      const double alpha = dot2(q, q) - 0.25 * d * d, beta = 2 * side_k;
      sum_ab += alpha * beta;
      sum_bb += beta * beta;
    }
    if (bulge == 0) return std::nullopt;
    // Under half a turn the centre is on the other side of the chord from
    // the bulge; with n to the left of A->B, a bulge to the left turns clockwise.
    const bool ccw = bulge < 0;
    Side side = Side::Both;
    if (level_sided) {
      // Material on the right: outside the circle of an arc turning left
      // (counter-clockwise), inside one turning right. The cut must stay on
      // the free side of the points: inside the circle's ring of points for
      // the first (as over a concave row), outside for the second (convex).
      side = ccw ? Side::Concave : Side::Convex;
    } else if (o_.material_below) {
      // Which way the points bulge in Z: up over a centre below (convex),
      // down under a centre above (concave).
      const double bulge_z = (ax.first == 2 ? n.a : n.b) * bulge;
      if (bulge_z == 0) return std::nullopt;
      side = bulge_z > 0 ? Side::Convex : Side::Concave;
    }
    auto direction_angle = [&](P2 c, P2 p) { return ccw ? ccw_angle(A - c, p - c) : ccw_angle(p - c, A - c); };

    // The centre, t along the chord's bisector: the feasible range of t is
    // where every point's window holds (a linear programme in t, with the
    // radius and the chords frozen at the previous guess); in it, the
    // least-squares circle (exact data: the exact circle), or else the
    // middle of the range. The centre is checked exactly below.
    if (!(sum_bb > 0)) return std::nullopt;
    const double t_ls = sum_ab / sum_bb;
    // First guess: the least-squares circle, on the far side of the chord
    // and within the radius cap.
    const double t_cap = std::sqrt(std::max(0.0, o_.max_radius * o_.max_radius - 0.25 * d * d));
    double t = std::clamp(t_ls, -t_cap, t_cap);
    if ((t > 0) == (bulge > 0) || t == 0) {
      const P2 q = at(far) - M;
      t = std::clamp((dot2(q, q) - 0.25 * d * d) / (2 * bulge), -t_cap, t_cap);
    }
    // Over a convex stretch an arc the controller cuts as one straight chord
    // is under the points: not worth a linear programme.
    if (side == Side::Convex && o_.controller_arc_tolerance > 0) {
      const double r = std::hypot(0.5 * d, t);
      const double c12 = o_.controller_arc_tolerance;
      const double sweep = 2 * std::asin(std::min(1.0, 0.5 * d / r));
      if (c12 < 2 * r && 0.5 * sweep * r / std::sqrt(c12 * (2 * r - c12)) < 1.5) return std::nullopt;
    }
    double tl = -HUGE_VAL, th = HUGE_VAL;
    for (int iter = 0; iter < 3; ++iter) {
      const double r = std::hypot(0.5 * d, t);
      if (!(r <= o_.max_radius)) return std::nullopt;
      const P2 c{M.a + t * n.a, M.b + t * n.b};
      const double sweep = direction_angle(c, B);
      if (!(sweep < std::numbers::pi)) return std::nullopt;
      const ChordModel chords(r, sweep, o_.controller_arc_tolerance);
      tl = -HUGE_VAL;
      th = HUGE_VAL;
      for (std::size_t k = i + 1; k < j; ++k) {
        const P2 q = at(k) - M;
        const P2 pk = at(k);
        const double rho = len2(pk - c);
        const double uz = side == Side::Both || level_sided || !(rho > 0)
                              ? 1.0
                              : std::fabs((ax.first == 2 ? pk.a - c.a : pk.b - c.b) / rho);
        const auto [glo, ghi] = window(side, r, chords.lowest_radius(direction_angle(c, pk)), 0, uz);
        if (!(ghi >= glo)) return std::nullopt;
        // g = r - rho in [glo, ghi]  <=>  rho^2 - r^2 = alpha - beta t in [flo, fhi].
        const double flo = -2 * r * ghi + ghi * ghi, fhi = -2 * r * glo + glo * glo;
        const double alpha = dot2(q, q) - 0.25 * d * d, beta = 2 * dot2(q, n);
        if (std::fabs(beta) < 1e-12) {
          if (alpha < flo || alpha > fhi) return std::nullopt;
          continue;
        }
        double a = (alpha - fhi) / beta, b = (alpha - flo) / beta;
        if (a > b) std::swap(a, b);
        tl = std::max(tl, a);
        th = std::min(th, b);
        if (!(tl <= th)) return std::nullopt;
      }
      if (side == Side::Concave) {
        // The points' segments must stay outside the circle too: their
        // midpoints here (rho >= r, alpha - beta t >= 0), exactly below.
        for (std::size_t k = i; k < j; ++k) {
          const P2 p0 = at(k), p1 = at(k + 1);
          const P2 q = P2{0.5 * (p0.a + p1.a), 0.5 * (p0.b + p1.b)} - M;
          const double alpha = dot2(q, q) - 0.25 * d * d, beta = 2 * dot2(q, n);
          if (std::fabs(beta) < 1e-12) {
            if (alpha < 0) return std::nullopt;
          } else if (beta > 0) {
            th = std::min(th, alpha / beta);
          } else {
            tl = std::max(tl, alpha / beta);
          }
        }
      }
      if (side != Side::Concave) {
        // Nor may the arc rise more than the tolerance over a long segment
        // between two points (a sparse straight stretch): points along it,
        // rho >= r - tol, alpha - beta t >= flo. Checked exactly below.
        for (std::size_t k = i; k < j; ++k) {
          const P2 p0 = at(k), p1 = at(k + 1);
          const int parts = int(std::clamp(std::ceil(len2(p1 - p0) / 0.25), 1.0, 16.0));
          for (int f = 1; f < parts || (parts == 1 && f == 1); ++f) {
            const double w = parts == 1 ? 0.5 : double(f) / parts;
            const P2 pw{p0.a + w * (p1.a - p0.a), p0.b + w * (p1.b - p0.b)};
            const double rho = len2(pw - c);
            const double uz = side == Side::Both || level_sided || !(rho > 0)
                                  ? 1.0
                                  : std::fabs((ax.first == 2 ? pw.a - c.a : pw.b - c.b) / rho);
            const double tol = o_.tolerance * uz, flo = -2 * r * tol + tol * tol;
            const P2 q = pw - M;
            const double alpha = dot2(q, q) - 0.25 * d * d, beta = 2 * dot2(q, n);
            if (std::fabs(beta) < 1e-12) {
              if (alpha < flo) return std::nullopt;
            } else if (beta > 0) {
              th = std::min(th, (alpha - flo) / beta);
            } else {
              tl = std::max(tl, (alpha - flo) / beta);
            }
          }
        }
      }
      if (!(tl <= th)) return std::nullopt;
      t = std::isfinite(tl) && std::isfinite(th) ? 0.5 * (tl + th) : std::clamp(t_ls, tl, th);
      // The centre stays on the far side of the chord (under half a turn).
      if ((t > 0) == (bulge > 0) || t == 0) return std::nullopt;
    }
    if (auto m = arc_with_centre(*plane, ax, i, j, std::clamp(t_ls, tl, th), M, n, ccw, side, level_sided)) return m;
    return arc_with_centre(*plane, ax, i, j, t, M, n, ccw, side, level_sided);
  }

 private:
  enum class Side { Both, Convex, Concave };

  // The arc from i to j about M + t n (rounded as written), if it holds exactly.
  // `level`: a one-sided run in its own plane (material_right): the window
  // is radial both ways, no vertical check.
  std::optional<FittedMove> arc_with_centre(Plane plane, const PlaneAxes& ax, std::size_t i, std::size_t j, double t,
                                            P2 M, P2 n, bool ccw, Side side, bool level) const {
    auto at = [&](std::size_t k) { return P2{component(pts_[k], ax.first), component(pts_[k], ax.second)}; };
    const P2 A = at(i), B = at(j);
    auto direction_angle = [&](P2 c, P2 p) { return ccw ? ccw_angle(A - c, p - c) : ccw_angle(p - c, A - c); };
    // The centre as it will be written: offsets from the start, rounded.
    const double step = o_.center_step;
    const P2 off{std::round((M.a + t * n.a - A.a) / step) * step, std::round((M.b + t * n.b - A.b) / step) * step};
    const P2 C{A.a + off.a, A.b + off.b};
    const double r = len2(A - C);
    if (!(r > 0) || !(r <= o_.max_radius)) return std::nullopt;
    // GRBL turns the start's radius about the centre and ends with a straight
    // move onto the target: the radius mismatch is a deviation at the end.
    const double dr = std::fabs(len2(B - C) - r);
    if (!(dr <= 1e-3)) return std::nullopt;
    const double sweep = direction_angle(C, B);
    if (!(sweep >= o_.min_sweep) || !(sweep < std::numbers::pi)) return std::nullopt;
    const ChordModel chords(r, sweep, o_.controller_arc_tolerance);
    // The controller's float arithmetic: a millionth of the radius.
    const double margin = dr + 1e-6 * r;
    double last = 0;
    for (std::size_t k = i + 1; k < j; ++k) {
      const P2 q = at(k);
      // In order along the arc, within it.
      const double phi = direction_angle(C, q);
      if (phi < last || phi > sweep) return std::nullopt;
      last = phi;
      const auto [glo, ghi] = window(side, r, chords.lowest_radius(phi), margin);
      const double g = r - len2(q - C);
      // Over material only the floor is radial; the ceiling is vertical, below.
      // Beside it (level) both are radial.
      if (!(g >= glo) || ((side == Side::Both || level) && !(g <= ghi))) return std::nullopt;
    }
    // Every segment between the points within the tolerance of the arc:
    // its point nearest the centre no further inside the circle. (Concave:
    // the segments are outside the circle, checked below; a straight
    // segment is nearest the circle's ring at an end, and the ends are
    // within the tolerance.)
    if (side == Side::Both || (level && side == Side::Convex))
      for (std::size_t k = i; k < j; ++k)
        if (r - distance_to_segment(C, at(k), at(k + 1)) > o_.tolerance - margin) return std::nullopt;
    if (side != Side::Both && !level && !within_vertically(ax, i, j, C, r, sweep, side, margin)) return std::nullopt;
    if (side != Side::Both && !level) {
      // The arc must stay on one half of its circle (a graph over the row):
      // the upper half over a centre below all points, the lower half under one above.
      const double cz = ax.first == 2 ? C.a : C.b;
      for (std::size_t k = i; k <= j; ++k)
        if (side == Side::Convex ? pts_[k].z < cz : pts_[k].z > cz) return std::nullopt;
    }
    // Convex: every point under (inside) the chord path, which with the
    // centre bounds a convex polygon, so the segments between them are too.
    // Concave: the segments must pass outside the circle (under the arc);
    // the chords run above (inside) the arc. The first and last segments
    // touch the circle where the cut starts and ends exactly; they must only
    // not enter it.
    if (side == Side::Concave)
      for (std::size_t k = i; k < j; ++k) {
        const double need = k == i ? r - 1e-9 : k + 1 == j ? std::min(r, r - dr) - 1e-9 : r + margin;
        if (distance_to_segment(C, at(k), at(k + 1)) < need) return std::nullopt;
      }

    FittedMove m;
    m.arc = true;
    m.to = pts_[j];
    m.plane = plane;
    m.clockwise = !ccw;
    component(m.center_offset, ax.first) = off.a;
    component(m.center_offset, ax.second) = off.b;
    m.radius = r;
    m.sweep = sweep;
    return m;
  }

  // The allowed g = r - rho (how far inside the circle a point may lie) for a
  // point where the controller's path runs between the circle and
  // `lowest` (its chords), each side narrowed by `margin`.
  // Over material: the highest the cut runs over each point and each
  // segment at most the tolerance above it, vertically. Convex: the arc
  // itself is highest (upper half, z = cz + sqrt(r^2 - h^2)). Concave: the
  // chords are, within the ring down to r - their largest sag.
  bool within_vertically(const PlaneAxes& ax, std::size_t i, std::size_t j, P2 C, double r, double sweep, Side side,
                         double margin) const {
    const bool z_first = ax.first == 2;
    auto sz = [&](std::size_t k) {
      const P2 p{component(pts_[k], ax.first), component(pts_[k], ax.second)};
      return z_first ? P2{p.b, p.a} : p;  // (row position, height)
    };
    const P2 c = z_first ? P2{C.b, C.a} : C;
    const double tol = o_.tolerance - margin;
    double rr = r;
    if (side == Side::Concave) {
      const ChordModel chords(r, sweep, o_.controller_arc_tolerance);
      rr = chords.deepest();
    }
    auto top = [&](double s, double& z) {
      const double h = s - c.a, q = rr * rr - h * h;
      if (!(q > 0)) return false;
      z = side == Side::Convex ? c.b + std::sqrt(q) : c.b - std::sqrt(q);
      return true;
    };
    for (std::size_t k = i; k <= j; ++k) {
      const P2 p = sz(k);
      double z = 0;
      if (!top(p.a, z) || z - p.b > tol) return false;
    }
    if (side == Side::Convex) {
      // Over a segment the gap is largest where the circle's slope is the segment's.
      for (std::size_t k = i; k < j; ++k) {
        const P2 p0 = sz(k), p1 = sz(k + 1);
        const double ds = p1.a - p0.a;
        if (ds == 0) continue;
        const double m = (p1.b - p0.b) / ds;
        const double s = c.a - m * r / std::sqrt(1 + m * m);
        if ((s - p0.a) * (s - p1.a) >= 0) continue;  // not inside the segment
        double z = 0;
        if (!top(s, z) || z - (p0.b + m * (s - p0.a)) > tol) return false;
      }
    }
    return true;
  }

  // Over material the tolerance is vertical (as the raster's): radially it
  // is tol times |uz|, the vertical part of the radius through the point
  // (1 elsewhere).
  std::pair<double, double> window(Side side, double r, double lowest, double margin, double uz = 1) const {
    const double tol = o_.tolerance * uz, sag = r - lowest;
    switch (side) {
      case Side::Convex: return {sag + margin, tol - margin};    // under the chords, within tol of the arc
      case Side::Concave: return {sag - tol + margin, -margin};  // under the arc, within tol of the chords
      default: return {sag - tol + margin, tol - margin};        // within tol of both
    }
  }

  // The run's plane: the coordinate all its points share.
  std::optional<Plane> plane_of(std::size_t i, std::size_t j) const {
    bool cx = true, cy = true, cz = true;
    const geometry::Vec3& p0 = pts_[i];
    for (std::size_t k = i + 1; k <= j && (cx || cy || cz); ++k) {
      cx = cx && pts_[k].x == p0.x;
      cy = cy && pts_[k].y == p0.y;
      cz = cz && pts_[k].z == p0.z;
    }
    if (cz) return Plane::XY;
    if (cy) return Plane::ZX;
    if (cx) return Plane::YZ;
    return std::nullopt;
  }

  const std::vector<geometry::Vec3>& pts_;
  const ArcFitOptions& o_;
};

}  // namespace

constexpr std::size_t kSearchSpan = 48;

namespace {

// One step of the greedy fit of points[..last]: the longest arc from i, else
// a line to the next point; returns the index the move ends at. It depends
// on i and last alone, so two greedy runs that meet at an index go on alike
// (fit_range's chunks rely on it).
std::size_t fit_step(const Fitter& fitter, const std::vector<geometry::Vec3>& points, std::size_t i, std::size_t last,
                     const ArcFitOptions& o, FittedMove& move) {
  const std::size_t min_span = std::max<std::size_t>(2, o.min_segments);
  std::optional<FittedMove> best;
  std::size_t best_j = i + 1;
  if (o.tolerance > 0 && i + min_span <= last) {
    // Longest arc from i: spans doubling while they fit, then halving back
    // between the longest that fitted and the next that did not. Short
    // spans may not fit where longer ones do (noise; a convex run under
    // the controller's few long chords), so failures are passed over up to
    // kSearchSpan points before the first fit.
    std::size_t ok = 0, bad = 0, span = min_span;
    while (i + span <= last) {
      if (auto a = fitter.arc(i, i + span)) {
        ok = span;
        best = a;
        bad = 0;
      } else {
        bad = span;
        if (ok > 0 || span >= kSearchSpan) break;
      }
      if (i + span == last) break;
      span = std::min(2 * span, last - i);
    }
    if (ok > 0 && bad > ok + 1) {
      std::size_t lo = ok, hi = bad;
      while (hi > lo + 1) {
        const std::size_t mid = lo + (hi - lo) / 2;
        if (auto a = fitter.arc(i, i + mid)) {
          lo = mid;
          best = a;
        } else {
          hi = mid;
        }
      }
      ok = lo;
    }
    if (best) best_j = i + ok;
  }
  if (best) {
    move = *best;
  } else {
    move = FittedMove{};
    move.to = points[i + 1];
  }
  return best_j;
}

// The moves of a greedy run from `from` on until it reaches `until` (at
// most last), each with the index it starts at.
struct GreedyRun {
  std::vector<std::size_t> starts;  // increasing
  std::vector<FittedMove> moves;
  std::size_t end = 0;              // the index the last move ends at
};

GreedyRun greedy_run(const Fitter& fitter, const std::vector<geometry::Vec3>& points, std::size_t from, std::size_t until,
                     std::size_t last, const ArcFitOptions& o) {
  GreedyRun r;
  std::size_t i = from;
  FittedMove m;
  while (i < until) {
    r.starts.push_back(i);
    i = fit_step(fitter, points, i, last, o, m);
    r.moves.push_back(m);
  }
  r.end = i;
  return r;
}

// Stretches longer than this are fitted in chunks, in parallel.
constexpr std::size_t kChunkPoints = 2048;

// The greedy fit of points[first..last] (the longest arc from each point,
// else a line to the next). A long stretch (a raster's rows and links, all
// at one height over a flat border, have no corner to cut them at) is
// fitted in chunks in parallel, each a greedy run from its first point until
// the next chunk's; the runs are then stitched: from where one run ends the
// fit goes on one step at a time until it meets an index the next run
// started a move at, and takes that run's moves from there. The greedy step
// depends only on its index, so the result is the serial fit's.
void fit_range(const Fitter& fitter, const std::vector<geometry::Vec3>& points, std::size_t first, std::size_t last,
               const ArcFitOptions& o, std::vector<FittedMove>& out) {
  const std::size_t chunks = o.parallel ? (last - first + kChunkPoints - 1) / kChunkPoints : 1;
  if (chunks <= 1) {
    GreedyRun r = greedy_run(fitter, points, first, last, last, o);
    out.insert(out.end(), r.moves.begin(), r.moves.end());
    return;
  }
  std::vector<GreedyRun> runs(chunks);
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
    const std::size_t from = first + c * kChunkPoints;
    runs[c] = greedy_run(fitter, points, from, std::min(last, from + kChunkPoints), last, o);
  });
  std::size_t i = first;
  FittedMove m;
  for (std::size_t c = 0; c < chunks && i < last; ++c) {
    const GreedyRun& r = runs[c];
    // Meet the run: step on until an index it started a move at, or past it.
    auto at = std::lower_bound(r.starts.begin(), r.starts.end(), i);
    while (i < r.end && (at == r.starts.end() || *at != i)) {
      i = fit_step(fitter, points, i, last, o, m);
      out.push_back(m);
      at = std::lower_bound(at, r.starts.end(), i);
    }
    if (i >= r.end) continue;
    const auto k = static_cast<std::size_t>(at - r.starts.begin());
    out.insert(out.end(), r.moves.begin() + static_cast<std::ptrdiff_t>(k), r.moves.end());
    i = r.end;
  }
  while (i < last) {
    i = fit_step(fitter, points, i, last, o, m);
    out.push_back(m);
  }
}

}  // namespace

std::vector<FittedMove> fit_arcs(const std::vector<geometry::Vec3>& points, const ArcFitOptions& o) {
  if (!(o.tolerance >= 0) || !(o.controller_arc_tolerance >= 0))
    throw std::invalid_argument("arc fit tolerances must not be negative");
  if (!(o.max_radius > 0) || !(o.center_step > 0) || !(o.min_sweep >= 0))
    throw std::invalid_argument("arc fit: radius cap, centre step and minimum sweep must be positive");
  std::vector<FittedMove> out;
  const std::size_t n = points.size();
  if (n < 2) return out;
  const Fitter fitter(points, o);
  // No arc passes through a corner (a point whose neighbours share no
  // coordinate with it): the greedy fit stops at every corner, so the
  // stretches between corners are fitted independently, in parallel, with
  // the same result.
  std::vector<std::size_t> cuts{0};
  for (std::size_t k = 1; k + 1 < n; ++k) {
    const geometry::Vec3 &a = points[k - 1], &b = points[k], &c = points[k + 1];
    const bool shared = (a.x == b.x && b.x == c.x) || (a.y == b.y && b.y == c.y) || (a.z == b.z && b.z == c.z);
    if (!shared) cuts.push_back(k);
  }
  cuts.push_back(n - 1);
  std::vector<std::vector<FittedMove>> parts(cuts.size() - 1);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, parts.size(), 16), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t p = r.begin(); p != r.end(); ++p) {
      parts[p].reserve(cuts[p + 1] - cuts[p]);
      fit_range(fitter, points, cuts[p], cuts[p + 1], o, parts[p]);
    }
  });
  std::size_t total = 0;
  for (const auto& part : parts) total += part.size();
  out.reserve(total);
  for (auto& part : parts) out.insert(out.end(), part.begin(), part.end());
  return out;
}

}  // namespace cncstream
