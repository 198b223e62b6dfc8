#pragma once
// An independent drop-cutter oracle for the CL engine tests. It shares no
// code with the engine (not even Cutter::profile_height): for one facet and
// one node it maximises the concave function p.z - h(|p_xy - c|) over the
// triangle intersected with the cutter's disc by nested golden-section search
// over barycentric coordinates. Every value it returns is attained at a real
// point of the facet, so it is a lower bound of the true drop height, accurate
// to about 1e-8 mm.
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include <vector>

#include "cncstream/geometry/mesh.hpp"
#include "cncstream/geometry/vec3.hpp"

namespace cl_oracle {

using cncstream::geometry::Vec3;

inline constexpr double kNone = -std::numeric_limits<double>::infinity();

struct Tool {
  double R, rk;  // radius, corner radius (flat: 0, ball: R)
  // Any other axisymmetric profile (V-bit, tapered ball): its height above
  // the tip at radius rho, written by the test from the shape's geometry.
  std::function<double(double)> profile = {};
  // xy distance up to which points count as reached.
  double reach() const { return R; }
  double h(double rho) const {
    if (profile) return profile(std::min(rho, R));
    const double rc = R - rk;
    if (rho <= rc) return 0.0;
    const double t = std::min(rho - rc, rk);
    return rk - std::sqrt(std::max(0.0, rk * rk - t * t));
  }
};

constexpr double kGolden = 0.6180339887498949;

// Maximise a concave f on [a, b]; returns the best value seen (attained).
template <class F>
double golden_max(F f, double a, double b, int iters) {
  double best = std::max(f(a), f(b));
  double x1 = b - kGolden * (b - a), x2 = a + kGolden * (b - a);
  double f1 = f(x1), f2 = f(x2);
  for (int k = 0; k < iters && b - a > 0; ++k) {
    best = std::max(best, std::max(f1, f2));
    if (f1 < f2) {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + kGolden * (b - a);
      f2 = f(x2);
    } else {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - kGolden * (b - a);
      f1 = f(x1);
    }
  }
  return std::max(best, std::max(f1, f2));
}

// Minimiser of a convex f on [a, b].
template <class F>
double golden_argmin(F f, double a, double b, int iters) {
  for (int k = 0; k < iters && b - a > 0; ++k) {
    const double x1 = b - kGolden * (b - a), x2 = a + kGolden * (b - a);
    if (f(x1) < f(x2)) b = x2; else a = x1;
  }
  return 0.5 * (a + b);
}

// Drop height of the tool at node (cx, cy) against triangle p0 p1 p2, or
// kNone when no point of it lies within the tool radius.
inline double facet_drop(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Tool& tool, double cx, double cy,
                         int iters = 90) {
  const Vec3 e1 = p1 - p0, e2 = p2 - p0;
  const double R2 = tool.reach() * tool.reach();
  // Points p(u, v) = p0 + u e1 + v e2, u in [0, 1], v in [0, 1 - u].
  auto A = [&](double u, double& ax, double& ay) {
    ax = p0.x + u * e1.x - cx;
    ay = p0.y + u * e1.y - cy;
  };
  const double bb = e2.x * e2.x + e2.y * e2.y;
  // Squared xy distance from c to the slice segment at u (convex in u).
  auto dist2 = [&](double u) {
    double ax, ay;
    A(u, ax, ay);
    double v = 0;
    if (bb > 0) v = std::clamp(-(ax * e2.x + ay * e2.y) / bb, 0.0, 1.0 - u);
    const double x = ax + v * e2.x, y = ay + v * e2.y;
    return x * x + y * y;
  };
  // Feasible v-interval of the slice at u.
  auto slice = [&](double u, double& vlo, double& vhi) {
    double ax, ay;
    A(u, ax, ay);
    vlo = 0;
    vhi = std::max(0.0, 1.0 - u);
    const double aa = ax * ax + ay * ay;
    if (bb == 0) return aa <= R2;
    const double ab = ax * e2.x + ay * e2.y;
    const double disc = ab * ab - bb * (aa - R2);
    if (disc < 0) return false;
    const double s = std::sqrt(disc);
    vlo = std::max(vlo, (-ab - s) / bb);
    vhi = std::min(vhi, (-ab + s) / bb);
    return vlo <= vhi;
  };
  auto f = [&](double u, double v) {
    const Vec3 p = p0 + e1 * u + e2 * v;
    const double rho2 = (p.x - cx) * (p.x - cx) + (p.y - cy) * (p.y - cy);
    if (rho2 > R2 * (1 + 1e-12)) return kNone;  // rounding of the slice ends
    return p.z - tool.h(std::sqrt(rho2));
  };
  auto F = [&](double u) {
    double vlo, vhi;
    if (!slice(u, vlo, vhi)) return kNone;
    return golden_max([&](double v) { return f(u, v); }, vlo, vhi, iters);
  };
  const double um = golden_argmin(dist2, 0.0, 1.0, 2 * iters);
  const double closest = dist2(um);
  if (closest > R2 * (1 + 1e-13)) return kNone;
  // A facet that only grazes the rim (the disc tangent to it, to rounding):
  // its closest point, which the slices below may miss.
  double graze = kNone;
  {
    double ax, ay;
    A(um, ax, ay);
    const double v = bb > 0 ? std::clamp(-(ax * e2.x + ay * e2.y) / bb, 0.0, 1.0 - um) : 0.0;
    graze = (p0 + e1 * um + e2 * v).z - tool.h(std::min(tool.R, std::sqrt(closest)));
  }
  if (closest > R2) return graze;
  // Feasible u-interval [ua, ub] by bisection on the convex dist2.
  double ua = 0, ub = 1;
  if (dist2(0.0) > R2) {
    double lo = 0, hi = um;
    for (int k = 0; k < 200 && hi - lo > 0; ++k) {
      const double mid = 0.5 * (lo + hi);
      if (mid == lo || mid == hi) break;
      (dist2(mid) > R2 ? lo : hi) = mid;
    }
    ua = hi;
  }
  if (dist2(1.0) > R2) {
    double lo = um, hi = 1;
    for (int k = 0; k < 200 && hi - lo > 0; ++k) {
      const double mid = 0.5 * (lo + hi);
      if (mid == lo || mid == hi) break;
      (dist2(mid) > R2 ? hi : lo) = mid;
    }
    ub = lo;
  }
  return std::max(graze, std::max(F(um), golden_max(F, ua, ub, iters)));
}

// XY distance from (x, y) to the triangle's projection.
inline double xy_distance(const Vec3& p0, const Vec3& p1, const Vec3& p2, double x, double y) {
  const Vec3* p[3] = {&p0, &p1, &p2};
  double best = HUGE_VAL;
  int pos = 0, neg = 0;
  for (int k = 0; k < 3; ++k) {
    const Vec3& a = *p[k];
    const Vec3& b = *p[(k + 1) % 3];
    const double ex = b.x - a.x, ey = b.y - a.y, ee = ex * ex + ey * ey;
    const double t = ee > 0 ? std::clamp(((x - a.x) * ex + (y - a.y) * ey) / ee, 0.0, 1.0) : 0.0;
    best = std::min(best, std::hypot(x - a.x - t * ex, y - a.y - t * ey));
    const double side = ex * (y - a.y) - ey * (x - a.x);
    pos += side > 0;
    neg += side < 0;
  }
  return (pos == 3 || neg == 3) ? 0.0 : best;
}

// Drop height against a segment (1-D, same method).
inline double segment_drop(const Vec3& a, const Vec3& b, const Tool& tool, double cx, double cy) {
  return facet_drop(a, b, b, tool, cx, cy);
}

struct MeshDrop {
  double drop = kNone;        // max over facets
  double distance = HUGE_VAL; // xy distance to the nearest facet
};

// Facet indices, highest top first.
inline std::vector<std::size_t> facets_by_top(const cncstream::geometry::Mesh& m) {
  std::vector<std::size_t> order(m.triangles.size());
  for (std::size_t f = 0; f < order.size(); ++f) order[f] = f;
  auto top = [&](std::size_t f) { return std::max({m.corner(f, 0).z, m.corner(f, 1).z, m.corner(f, 2).z}); };
  std::sort(order.begin(), order.end(), [&](std::size_t p, std::size_t q) { return top(p) > top(q); });
  return order;
}

// Max over facets of the oracle's drop at (x, y). Facets are visited highest
// first and skipped when even their top minus the profile height at their
// nearest point cannot beat the best so far.
inline MeshDrop mesh_drop(const cncstream::geometry::Mesh& m, const std::vector<std::size_t>& by_top, const Tool& t, double x,
                          double y) {
  MeshDrop r;
  for (std::size_t f : by_top) {
    const Vec3 a = m.corner(f, 0), b = m.corner(f, 1), c = m.corner(f, 2);
    const double top = std::max({a.z, b.z, c.z});
    if (top < r.drop - 1e-9 && r.distance < t.R) break;  // nothing lower can win
    if (std::min({a.x, b.x, c.x}) > x + t.R || std::max({a.x, b.x, c.x}) < x - t.R ||
        std::min({a.y, b.y, c.y}) > y + t.R || std::max({a.y, b.y, c.y}) < y - t.R) {
      continue;
    }
    const double d = xy_distance(a, b, c, x, y);
    r.distance = std::min(r.distance, d);
    if (d > t.reach()) continue;
    if (top - t.h(std::min(d, t.R)) < r.drop - 1e-9) continue;
    r.drop = std::max(r.drop, facet_drop(a, b, c, t, x, y));
  }
  return r;
}

}  // namespace cl_oracle
