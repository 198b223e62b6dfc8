#include "cl_contact.hpp"

#include <algorithm>
#include <cmath>

namespace cncstream::cl_detail {

Vec3 upward_normal(const Vec3& p0, const Vec3& p1, const Vec3& p2) {
  const Vec3 n = cross(p1 - p0, p2 - p0);
  const double len = norm(n);
  if (!(len > 0)) return {};
  const Vec3 u = n / len;
  return u.z < 0 ? -u : u;
}

FaceOffset face_offset(const Vec3& p0, const Vec3& p1, const Vec3& p2, const CutterShape& cutter) {
  FaceOffset f;
  const Vec3 e1 = p1 - p0, e2 = p2 - p0;
  const Vec3 nn = cross(e1, e2);
  const double len = norm(nn);
  if (!(len > 0) || !std::isfinite(len)) return f;
  Vec3 n = nn / len;
  if (n.z < 0) n = -n;
  if (n.z < kVerticalNz) return f;
  const double nxy = std::hypot(n.x, n.y);
  f.nz = n.z;
  f.horizontal = nxy < kHorizontalNxy;

  // Offset vector, thesis eq. 3.3: rk * n plus rc along the horizontal part
  // of n. The contact point is c - shift (xy).
  double sx = cutter.rk * n.x, sy = cutter.rk * n.y;
  if (!f.horizontal && cutter.rc > 0) {
    sx += cutter.rc * n.x / nxy;
    sy += cutter.rc * n.y / nxy;
  }
  const Vec3* p[3] = {&p0, &p1, &p2};
  for (int k = 0; k < 3; ++k) {
    f.qx[k] = p[k]->x + sx;
    f.qy[k] = p[k]->y + sy;
  }
  const double area2 = (f.qx[1] - f.qx[0]) * (f.qy[2] - f.qy[0]) - (f.qy[1] - f.qy[0]) * (f.qx[2] - f.qx[0]);
  // An XY triangle too thin for its orientation to be trusted contributes
  // through its edges only (its interior lies within rounding of them).
  double side2 = 0;
  for (int k = 0; k < 3; ++k) {
    const int k1 = (k + 1) % 3;
    side2 = std::fmax(side2, (f.qx[k1] - f.qx[k]) * (f.qx[k1] - f.qx[k]) + (f.qy[k1] - f.qy[k]) * (f.qy[k1] - f.qy[k]));
  }
  if (!(std::fabs(area2) > kThinXy * side2)) return FaceOffset{};
  if (area2 < 0) {
    std::swap(f.qx[1], f.qx[2]);
    std::swap(f.qy[1], f.qy[2]);
  }
  for (int k = 0; k < 3; ++k) {
    const int k1 = (k + 1) % 3;
    const double ex = f.qx[k1] - f.qx[k], ey = f.qy[k1] - f.qy[k];
    const double el = std::hypot(ex, ey);
    if (!(el > 0)) return FaceOffset{};
    f.inx[k] = -ey / el;
    f.iny[k] = ex / el;
  }

  // Plane height z(p) = p0.z + gx (p.x - p0.x) + gy (p.y - p0.y); the tip
  // sits rk (1 - n_z) below the contact point.
  f.gx = -n.x / n.z;
  f.gy = -n.y / n.z;
  f.ox = p0.x + sx;
  f.oy = p0.y + sy;
  f.z0 = p0.z - cutter.rk * (1.0 - n.z);

  // Inclusive test: when the contact point lies on a side shared with a
  // coplanar or concave neighbour, that side's edge is not drawn, so one of
  // the two facets must accept it despite rounding. The tolerance covers the
  // rounding of the shifted vertices, which grows with the error of the
  // contact direction n_xy / |n_xy| for small |n_xy|. Steep facets get none:
  // their slope would turn it into a height error (their edges are drawn).
  if (n.z >= kSteepNz) {
    double scale = 1.0;
    for (const Vec3* q : p) scale = std::fmax(scale, std::fmax(std::fabs(q->x), std::fmax(std::fabs(q->y), std::fabs(q->z))));
    const double eps_n = 4e-16 * scale * (norm(e1) + norm(e2)) / len;
    f.tol = 1e-12 * scale + 100.0 * cutter.R * eps_n;
    if (!f.horizontal && cutter.rc > 0) f.tol += 100.0 * cutter.rc * eps_n / nxy;
  }
  f.active = true;
  return f;
}

EdgeGeom make_edge(const Vec3& a, const Vec3& b) {
  EdgeGeom e;
  e.ax = a.x;
  e.ay = a.y;
  e.az = a.z;
  e.zmax = std::fmax(a.z, b.z);
  e.xmin = std::fmin(a.x, b.x);
  e.xmax = std::fmax(a.x, b.x);
  e.ymin = std::fmin(a.y, b.y);
  e.ymax = std::fmax(a.y, b.y);
  const double dx = b.x - a.x, dy = b.y - a.y;
  e.L = std::hypot(dx, dy);
  if (e.L > 0) {
    e.ux = dx / e.L;
    e.uy = dy / e.L;
    e.dz = b.z - a.z;
  } else {
    // A vertical edge touches the cutter first at its top end.
    e.az = e.zmax;
  }
  return e;
}

namespace {

// Slope of the bull-nose profile, h'(rho), for rho > rc.
inline double profile_slope(const CutterShape& c, double rho) {
  const double u = rho - c.rc;
  if (u <= 0) return 0.0;
  const double q = (c.rk - u) * (c.rk + u);
  if (q <= 0) return HUGE_VAL;
  return u / std::sqrt(q);
}

inline double profile_curvature(const CutterShape& c, double rho) {
  const double u = rho - c.rc;
  if (u <= 0) return 0.0;
  const double q = (c.rk - u) * (c.rk + u);
  if (q <= 0) return HUGE_VAL;
  return c.rk * c.rk / (q * std::sqrt(q));
}

// Maximiser over v in [a, b] of  G(v) = m v - h(sqrt(d2 + v^2)), m >= 0:
// a concave function, so its derivative is monotone; safeguarded Newton on
// the derivative, bracketed by bisection, converges to rounding level.
double bull_argmax(const CutterShape& c, double m, double d2, double a, double b) {
  if (b <= 0) return b;  // G' >= m >= 0 for v <= 0
  if (m == 0) return std::clamp(0.0, a, b);
  double lo = std::fmax(a, 0.0);
  if (d2 < c.rc * c.rc) lo = std::fmax(lo, std::sqrt(c.rc * c.rc - d2));  // flat bottom: G' = m > 0
  if (lo >= b) return b;
  auto dG = [&](double v) {
    const double rho = std::sqrt(d2 + v * v);
    if (rho <= 0) return m;
    return m - profile_slope(c, rho) * v / rho;
  };
  if (dG(lo) <= 0) return lo;
  double hi = b;
  if (dG(hi) >= 0) return hi;
  double v = 0.5 * (lo + hi);
  const double eps = 1e-15 * (c.R + std::fabs(lo) + std::fabs(hi));
  for (int iter = 0; iter < 200; ++iter) {
    const double rho = std::sqrt(d2 + v * v);
    const double H = profile_slope(c, rho);
    const double g = m - H * v / rho;
    if (g > 0) lo = v; else hi = v;
    if (g == 0 || hi - lo <= eps) break;
    const double dg = -(profile_curvature(c, rho) * v * v / (rho * rho) + H * d2 / (rho * rho * rho));
    double vn = v - g / dg;
    if (!(vn > lo && vn < hi)) vn = 0.5 * (lo + hi);
    if (std::fabs(vn - v) <= eps) {
      v = vn;
      break;
    }
    v = vn;
  }
  return v;
}

}  // namespace

double edge_drop(const EdgeGeom& e, const CutterShape& c, double x, double y) {
  const double px = x - e.ax, py = y - e.ay;
  if (e.L == 0) {
    const double rho2 = px * px + py * py;
    if (rho2 > c.R * c.R) return kNoContact;
    return e.az - c.h(std::sqrt(rho2));
  }
  const double s0 = px * e.ux + py * e.uy;
  const double d = px * e.uy - py * e.ux;
  const double d2 = d * d;
  const double R2 = c.R * c.R;
  if (d2 > R2) return kNoContact;
  const double w = std::sqrt(R2 - d2);
  const double lo = std::fmax(0.0, s0 - w), hi = std::fmin(e.L, s0 + w);
  if (lo > hi) return kNoContact;

  // Height along the clipped segment, evaluated from s in [0, L] so steep
  // edges lose nothing to cancellation.
  auto value = [&](double s) {
    const double v = s - s0;
    return e.az + e.dz * (s / e.L) - c.h(std::sqrt(d2 + v * v));
  };
  if (c.rk == 0) return value(e.dz > 0 ? hi : lo);  // flat: h = 0 on the disc
  const double vlo = lo - s0, vhi = hi - s0;
  if (c.rc == 0) {
    // Ball: the cylinder's maximiser in closed form.
    const double vstar = e.dz * w / std::hypot(e.L, e.dz);
    return value(std::clamp(s0 + std::clamp(vstar, vlo, vhi), lo, hi));
  }
  const double m = e.dz / e.L;
  double v;
  if (m >= 0) {
    v = bull_argmax(c, m, d2, vlo, vhi);
  } else {
    v = -bull_argmax(c, -m, d2, -vhi, -vlo);
  }
  return value(std::clamp(s0 + v, lo, hi));
}

double rect_segment_distance(const EdgeGeom& e, double x0, double y0, double x1, double y1) {
  const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
  const double half_diag = 0.5 * std::hypot(x1 - x0, y1 - y0);
  const double px = cx - e.ax, py = cy - e.ay;
  double dist;
  if (e.L == 0) {
    dist = std::hypot(px, py);
  } else {
    const double s = std::clamp(px * e.ux + py * e.uy, 0.0, e.L);
    dist = std::hypot(px - s * e.ux, py - s * e.uy);
  }
  return std::fmax(0.0, dist - half_diag);
}

}  // namespace cncstream::cl_detail
