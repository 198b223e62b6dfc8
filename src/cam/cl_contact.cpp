#include "cl_contact.hpp"

#include <algorithm>
#include <cmath>

namespace cncstream::cam::cl_detail {

geometry::Vec3 upward_normal(const geometry::Vec3& p0, const geometry::Vec3& p1, const geometry::Vec3& p2) {
  const geometry::Vec3 n = cross(p1 - p0, p2 - p0);
  const double len = norm(n);
  if (!(len > 0)) return {};
  const geometry::Vec3 u = n / len;
  return u.z < 0 ? -u : u;
}

FaceOffset face_offset(const geometry::Vec3& p0, const geometry::Vec3& p1, const geometry::Vec3& p2, const CutterShape& cutter) {
  FaceOffset f;
  const geometry::Vec3 e1 = p1 - p0, e2 = p2 - p0;
  const geometry::Vec3 nn = cross(e1, e2);
  const double len = norm(nn);
  if (!(len > 0) || !std::isfinite(len)) return f;
  geometry::Vec3 n = nn / len;
  if (n.z < 0) n = -n;
  if (n.z < kVerticalNz) return f;
  const double nxy = std::sqrt(n.x * n.x + n.y * n.y);
  f.nz = n.z;
  f.horizontal = nxy < kHorizontalNxy;

  // Offset vector, thesis eq. 3.3: rk * n plus rc along the horizontal part
  // of n. The contact point is c - shift (xy). A general profile: its
  // contact radius along the horizontal part of n.
  double sx = cutter.rk * n.x, sy = cutter.rk * n.y;
  PlaneContact pc;
  if (cutter.general) {
    pc = plane_contact(cutter.prof, f.horizontal ? 0.0 : nxy, n.z);
    f.ambiguous = pc.ambiguous;
    sx = sy = 0;
    if (!f.horizontal && pc.rho > 0) {
      sx = pc.rho * n.x / nxy;
      sy = pc.rho * n.y / nxy;
    }
  } else if (!f.horizontal && cutter.rc > 0) {
    sx += cutter.rc * n.x / nxy;
    sy += cutter.rc * n.y / nxy;
  }
  const geometry::Vec3* p[3] = {&p0, &p1, &p2};
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
    const double el = std::sqrt(ex * ex + ey * ey);
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
  f.z0 = cutter.general ? p0.z - pc.h : p0.z - cutter.rk * (1.0 - n.z);

  // Inclusive test: when the contact point lies on a side shared with a
  // coplanar or concave neighbour, that side's edge is not drawn, so one of
  // the two facets must accept it despite rounding. The tolerance covers the
  // rounding of the shifted vertices, which grows with the error of the
  // contact direction n_xy / |n_xy| for small |n_xy|. Steep facets get none:
  // their slope would turn it into a height error (their edges are drawn).
  if (n.z >= kSteepNz) {
    double scale = 1.0;
    for (const geometry::Vec3* q : p) scale = std::fmax(scale, std::fmax(std::fabs(q->x), std::fmax(std::fabs(q->y), std::fabs(q->z))));
    const double eps_n = 4e-16 * scale * (norm(e1) + norm(e2)) / len;
    f.tol = 1e-12 * scale + 100.0 * cutter.R * eps_n;
    if (!f.horizontal && cutter.rc > 0) f.tol += 100.0 * (cutter.general ? pc.rho : cutter.rc) * eps_n / nxy;
  }
  f.active = true;
  return f;
}

EdgeGeom make_edge(const geometry::Vec3& a, const geometry::Vec3& b) {
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
  e.L = std::sqrt(dx * dx + dy * dy);
  if (e.L > 0) {
    e.ux = dx / e.L;
    e.uy = dy / e.L;
    e.dz = b.z - a.z;
    e.inv_L = 1.0 / e.L;
    e.sin_slope = e.dz / std::sqrt(e.L * e.L + e.dz * e.dz);
  } else {
    // A vertical edge touches the cutter first at its top end.
    e.az = e.zmax;
  }
  return e;
}

namespace detail_cl_contact {

// Bull-nose against the infinite line through an edge: how far uphill of the
// node (along the edge's XY direction) the torus touches it. The contact
// normal N is perpendicular to the edge; with u the sine of N's tilt out of
// the edge's vertical plane and k the sine of the edge's slope, the contact
// point's XY distance from the line through the node is
//   g(u) = u (rk + rc / sqrt(u^2 + k^2 (1 - u^2))),
// which rises monotonically from 0 to R, so |d| = g(u) has one root: Newton
// safeguarded by bisection. The contact then lies k cos(theta) (rk + rc/|N_xy|)
// uphill. (This is the offset-ellipse problem, reduced to one monotone
// equation.)
double torus_line_contact_offset(double rc, double rk, double R, double k, double ad) {
  if (k <= 0) return 0.0;  // horizontal edge: the nearest point is best
  const double k2 = k * k;
  // With phi(u) = u / sqrt(u^2 + k^2 (1 - u^2)) >= u:  R u <= g(u) <= R phi(u),
  // which brackets the root; g is concave, so Newton from the right end
  // approaches it monotonically.
  const double y = std::min(1.0, ad / R);
  double lo = y * k / std::sqrt(std::max(1e-300, 1 - y * y * (1 - k2))), hi = y, u = y;
  if (!(lo <= hi)) lo = 0;
  for (int iter = 0; iter < 100; ++iter) {
    const double q = u * u + k2 * (1 - u * u);
    const double sq = std::sqrt(q);
    const double gval = u * (rk + rc / sq) - ad;
    if (gval > 0) hi = u; else lo = u;
    if (gval == 0) break;
    double un = u - gval / (rk + rc * k2 / (q * sq));
    if (!(un > lo && un < hi)) un = 0.5 * (lo + hi);
    const bool done = std::fabs(un - u) <= 4e-16 || hi - lo <= 4e-16;
    u = un;
    if (done) break;
  }
  const double cos_t = std::sqrt(std::max(0.0, (1 - u) * (1 + u)));
  const double nxy = std::sqrt(u * u + k2 * (1 - u * u));
  return k * cos_t * (rk + rc / nxy);
}

// Slope dh/drho of a band at rho (infinite at an arc's rim).
double band_slope(const ProfileBand& b, double rho) {
  if (b.kind == ProfileBand::Kind::Cone) return b.slope;
  const double u = std::clamp(rho - b.a, 0.0, b.r);
  const double w = std::sqrt(std::max(0.0, (b.r - u) * (b.r + u)));
  return w > 0 ? u / w : HUGE_VAL;
}

}  // namespace detail_cl_contact

PlaneContact plane_contact(const CutterProfile& p, double nxy, double nz) {
  // Ambiguity margin: a plane within rounding of a cone band's slope.
  constexpr double kSame = 1e-9;
  for (std::size_t k = 0; k < p.count; ++k) {
    const ProfileBand& b = p.band[k];
    if (nxy < b.sin0 - (b.kind == ProfileBand::Kind::Cone ? kSame : 0.0)) return {b.rho0, b.h0, false};  // a kink
    if (b.kind == ProfileBand::Kind::Cone) {
      if (nxy > b.sin1 + kSame) continue;
      // The plane's slope is the cone's, to rounding: the exact side's end.
      const bool outer = nxy > b.sin1;
      return {outer ? b.rho1 : b.rho0, outer ? b.h(b.rho1) : b.h0, true};
    }
    if (nxy > b.sin1) continue;
    if (nxy <= b.sin0) return {b.rho0, b.h0, false};
    return {b.a + b.r * nxy, b.zc - b.r * nz, false};
  }
  return {p.R, p.top, false};
}

double line_contact_offset(const CutterProfile& p, double k, double ad) {
  using detail_cl_contact::band_slope;
  // With t = tan(slope), the maximiser is where t = G(v) = h'(rho) v / rho,
  // rho = sqrt(ad^2 + v^2). h' and v / rho never decrease with v (h is
  // convex), so G is monotone: find the band where it crosses t, then solve
  // there in closed form (cone, sphere) or by the torus's monotone equation.
  if (!(k > 0)) return 0.0;  // level edge: the nearest point is best
  const double c = std::sqrt(std::max(0.0, (1 - k) * (1 + k)));
  const double t = c > 0 ? k / c : HUGE_VAL;
  auto v_at = [&](double rho) { return std::sqrt(std::max(0.0, (rho - ad) * (rho + ad))); };
  auto G = [&](const ProfileBand& b, double rho) { return rho > 0 ? band_slope(b, rho) * (v_at(rho) / rho) : 0.0; };
  for (std::size_t i = 0; i < p.count; ++i) {
    const ProfileBand& b = p.band[i];
    if (b.rho1 <= ad) continue;  // all of the band lies nearer the axis than the line
    const double rho_s = std::max(b.rho0, ad);
    if (t <= G(b, rho_s)) return v_at(rho_s);  // at the kink where the band begins
    if (!(t <= G(b, b.rho1))) continue;
    const double vs = v_at(rho_s), ve = v_at(b.rho1);
    double v;
    if (b.kind == ProfileBand::Kind::Cone) {
      // m v / rho = t  ->  v = t ad / sqrt(m^2 - t^2)   (m > t here).
      const double m = b.slope;
      v = ad * k / std::sqrt(std::max(1e-300, (m - t) * (m + t))) / (c > 0 ? c : 1e-300);
      if (!std::isfinite(v)) v = ve;
    } else if (b.a == 0) {
      // Sphere: the cylinder's maximiser, v = sqrt(r^2 - ad^2) sin(slope).
      v = std::sqrt(std::max(0.0, (b.r - ad) * (b.r + ad))) * k;
    } else {
      v = detail_cl_contact::torus_line_contact_offset(b.a, b.r, b.a + b.r, k, ad);
    }
    return std::clamp(v, vs, ve);
  }
  return v_at(p.R);  // the rim
}

double edge_drop(const EdgeGeom& e, const CutterShape& c, double x, double y, double current) {
  const double px = x - e.ax, py = y - e.ay;
  const double R2 = c.R * c.R;
  if (e.L == 0) {
    const double rho2 = px * px + py * py;
    if (rho2 > R2) return kNoContact;
    return e.az - c.h(std::sqrt(rho2));
  }
  const double d = px * e.uy - py * e.ux;
  const double d2 = d * d;
  if (d2 > R2) return kNoContact;
  const double s0 = px * e.ux + py * e.uy;
  const double w = std::sqrt(R2 - d2);
  const double lo = std::max(0.0, s0 - w), hi = std::min(e.L, s0 + w);
  if (lo > hi) return kNoContact;

  // Heights along the clipped segment are taken from s in [0, L], so steep
  // edges lose nothing to cancellation.
  if (!c.general && c.rk == 0) return e.az + e.dz * ((e.dz > 0 ? hi : lo) * e.inv_L);  // flat: h = 0 on the disc
  if (!c.general && c.rc == 0) {
    // Ball: the cylinder's maximiser in closed form, v = w sin(slope).
    const double s = std::clamp(s0 + w * e.sin_slope, lo, hi);
    const double v = s - s0;
    return e.az + e.dz * (s * e.inv_L) - c.R + std::sqrt(std::max(0.0, (w - v) * (w + v)));
  }
  const double vlo = lo - s0, vhi = hi - s0;
  // Before the iterative solve: the highest point of the clipped segment
  // minus the profile height at its nearest point bounds the result.
  const double top = e.az + e.dz * ((e.dz > 0 ? hi : lo) * e.inv_L);
  const double v_near = std::clamp(0.0, vlo, vhi);
  if (!profile_below(c, d2 + v_near * v_near, top - current)) return kNoContact;
  const double offset = c.general ? line_contact_offset(c.prof, std::fabs(e.sin_slope), std::fabs(d))
                                  : detail_cl_contact::torus_line_contact_offset(c.rc, c.rk, c.R, std::fabs(e.sin_slope), std::fabs(d));
  // The maximiser on the clipped segment: the line's contact clamped to it
  // (the function is concave along the segment).
  const double s = std::clamp(e.dz >= 0 ? s0 + offset : s0 - offset, lo, hi);
  const double vs = s - s0;
  return e.az + e.dz * (s * e.inv_L) - c.h(std::sqrt(d2 + vs * vs));
}

double rect_segment_distance(const EdgeGeom& e, double x0, double y0, double x1, double y1) {
  // Distance between the rectangle and the segment, attained at a segment end
  // point or a rectangle corner unless they meet; where the line crosses the
  // rectangle and the extents overlap, 0 (conservative: a lower bound).
  const double bx = e.ax + e.ux * e.L, by = e.ay + e.uy * e.L;
  auto point_rect2 = [&](double px, double py) {
    const double dx = std::max(0.0, std::max(x0 - px, px - x1)), dy = std::max(0.0, std::max(y0 - py, py - y1));
    return dx * dx + dy * dy;
  };
  double best = std::min(point_rect2(e.ax, e.ay), point_rect2(bx, by));
  if (best == 0 || e.L == 0) return std::sqrt(best);
  // Corners against the segment; sign changes of the corners' side of the
  // line with the segment's projection overlapping mean they intersect.
  const double cx[4] = {x0, x1, x1, x0}, cy[4] = {y0, y0, y1, y1};
  int pos = 0, neg = 0;
  for (int k = 0; k < 4; ++k) {
    const double px = cx[k] - e.ax, py = cy[k] - e.ay;
    const double side = px * e.uy - py * e.ux;
    pos += side > 0;
    neg += side < 0;
    const double s = std::clamp(px * e.ux + py * e.uy, 0.0, e.L);
    const double qx = px - s * e.ux, qy = py - s * e.uy;
    best = std::min(best, qx * qx + qy * qy);
  }
  if (pos && neg) {
    // The line crosses the rectangle; the segment does if its extent along
    // the line overlaps the rectangle's (it does not contain an end point).
    const double tmin = std::min({(x0 - e.ax) * e.ux + (y0 - e.ay) * e.uy, (x1 - e.ax) * e.ux + (y0 - e.ay) * e.uy,
                                  (x1 - e.ax) * e.ux + (y1 - e.ay) * e.uy, (x0 - e.ax) * e.ux + (y1 - e.ay) * e.uy});
    const double tmax = std::max({(x0 - e.ax) * e.ux + (y0 - e.ay) * e.uy, (x1 - e.ax) * e.ux + (y0 - e.ay) * e.uy,
                                  (x1 - e.ax) * e.ux + (y1 - e.ay) * e.uy, (x0 - e.ax) * e.ux + (y1 - e.ay) * e.uy});
    if (tmax >= 0 && tmin <= e.L) return 0.0;
  }
  return std::sqrt(best);
}

}  // namespace cncstream::cam::cl_detail
