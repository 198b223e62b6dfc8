#pragma once
// Exact drop heights of a generalized APT cutter (tool axis +Z, tip = lowest
// point) against one facet interior, one edge and one vertex. Internal to
// the CL engine; the grid rasterizer and the point query share these so a
// grid node and height_at() at the same (x, y) agree bit for bit.
//
// The drop height against a point set S at node c is
//   max over p in S with rho = |p_xy - c| <= R of  p.z - h(rho),
// h the cutter's profile height. h(|q - c|) is convex in q, so the function
// is concave over any convex piece of S: a facet's maximum is the tangent
// point of its plane (if inside the facet) or lies on its boundary, an edge
// is a 1-D concave maximisation.
#include <algorithm>
#include <cmath>
#include <limits>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/geometry/vec3.hpp"

namespace cncstream::cam::cl_detail {

inline constexpr double kNoContact = -std::numeric_limits<double>::infinity();

// The cutter as the contact formulas see it. Flat, ball and bull-nose use
// the closed forms of the generalized APT cutter (rk, rc); every other
// profile (V-bit, tapered ball, grown ones) is `general`: a list of bands
// (cutter.hpp), each with its own exact facet, edge and vertex contact.
struct CutterShape {
  double R = 0;   // radius (reach)
  double rk = 0;  // corner radius (APT)
  double rc = 0;  // core radius, R - rk (APT)
  bool general = false;
  CutterProfile prof;  // general: the bands

  // force_general: use the band formulas for an APT cutter too (tests
  // compare both).
  explicit CutterShape(const Cutter& c, bool force_general = false)
      : R(c.radius),
        rk(c.type == CutterType::Flat ? 0.0
           : c.type == CutterType::Ball ? c.radius
                                         : std::fmin(std::fmax(c.corner_radius, 0.0), c.radius)),
        rc(R - rk),
        general(force_general || !c.is_apt()) {
    if (general) {
      prof = c.profile();
      R = prof.R;
      rk = 0;
      rc = R;
    }
  }

  // Profile height above the tip at radius rho, 0 <= rho <= R (clamped).
  double h(double rho) const {
    if (general) return prof.h(rho);
    if (rho <= rc) return 0.0;
    const double u = std::min(rho - rc, rk);
    return rk - std::sqrt(std::max(0.0, (rk - u) * (rk + u)));
  }
  // Height of the profile at the rim (its maximum).
  double top() const { return general ? prof.top : rk; }
};

// Whether h(rho) < t, from rho^2 (cheap: no square root for flat and ball).
inline bool profile_below(const CutterShape& c, double rho2, double t) {
  if (c.general) return t > c.prof.top || c.prof.h(std::sqrt(rho2)) < t;
  if (t > c.rk) return true;  // h <= rk everywhere
  if (c.rc == 0) return c.R * c.R - rho2 > (c.R - t) * (c.R - t);
  if (rho2 <= c.rc * c.rc) return t > 0;
  const double u = std::sqrt(rho2) - c.rc;
  return (c.rk - u) * (c.rk + u) > (c.rk - t) * (c.rk - t);
}

// Where a general profile touches a plane whose upward unit normal has
// horizontal length nxy and vertical part nz: the radius rho at which the
// profile's tilt matches the plane's (inside an arc band rho = a + r nxy; at
// a kink, or on a cone band of the plane's own slope, its inner end; past
// the last band, the rim) and the profile height there. `ambiguous`: the
// plane's slope equals a straight band's (to rounding), so a whole segment
// of the band touches and the reported point is one of many.
struct PlaneContact {
  double rho = 0, h = 0;
  bool ambiguous = false;
};
PlaneContact plane_contact(const CutterProfile& p, double nxy, double nz);

// How far uphill of the node, along an edge's xy direction, a general
// profile touches the infinite line through the edge: the edge rises at
// sin(slope) = k >= 0, the node lies ad >= 0 from the line in xy. The
// maximiser of z(v) - h(sqrt(ad^2 + v^2)) (concave in v), unclamped.
double line_contact_offset(const CutterProfile& p, double k, double ad);

// Facet interior contact ("face offset"). For nodes c with c - shift inside
// the facet's xy triangle (within tol), the facet's drop height is linear in
// c: value(c) = z0 + gx * (c.x - ox) + gy * (c.y - oy).
struct FaceOffset {
  bool active = false;       // false: (near-)vertical or degenerate facet
  bool horizontal = false;   // treated as exactly horizontal (no shift)
  double qx[3] = {}, qy[3] = {};  // shifted triangle, counter-clockwise
  double inx[3] = {}, iny[3] = {};  // unit inward normals of its sides
  double ox = 0, oy = 0, z0 = 0, gx = 0, gy = 0;
  double tol = 0;            // inclusion tolerance, mm
  double nz = 0;             // upward unit normal's z
  bool ambiguous = false;    // general profile: a band of the facet's slope touches (see PlaneContact)

  bool contains(double x, double y) const {
    for (int k = 0; k < 3; ++k)
      if ((x - qx[k]) * inx[k] + (y - qy[k]) * iny[k] < -tol) return false;
    return true;
  }
  double value(double x, double y) const { return z0 + gx * (x - ox) + gy * (y - oy); }
  double xmin() const { return std::min(qx[0], std::min(qx[1], qx[2])) - tol; }
  double xmax() const { return std::max(qx[0], std::max(qx[1], qx[2])) + tol; }
  double ymin() const { return std::min(qy[0], std::min(qy[1], qy[2])) - tol; }
  double ymax() const { return std::max(qy[0], std::max(qy[1], qy[2])) + tol; }
};

// Facets whose upward unit normal has n_z below this are treated as vertical:
// their interior contact differs from their boundary's by O(R * n_z), and
// their plane height is too ill-conditioned to evaluate.
inline constexpr double kVerticalNz = 1e-8;
// XY triangles with twice their area below this times their longest side
// squared are too thin to orient reliably: drawn through their edges only.
inline constexpr double kThinXy = 1e-9;
// Facets steeper than this (n_z below it) never let an adjacent edge be
// skipped, and get no inclusion tolerance (slope would amplify it).
inline constexpr double kSteepNz = 0.01;
// |n_xy| below this: the facet counts as horizontal, so a flat or bull-nose
// cutter's contact direction (n_xy / |n_xy|, ill-defined there) is not used.
inline constexpr double kHorizontalNxy = 1e-9;

FaceOffset face_offset(const geometry::Vec3& p0, const geometry::Vec3& p1, const geometry::Vec3& p2, const CutterShape& cutter);

// Upward unit normal (n_z >= 0) of a triangle; zero vector if degenerate.
geometry::Vec3 upward_normal(const geometry::Vec3& p0, const geometry::Vec3& p1, const geometry::Vec3& p2);

// A mesh edge prepared for repeated drop queries.
struct EdgeGeom {
  double ax = 0, ay = 0, az = 0;  // start point
  double dz = 0;                  // b.z - a.z
  double ux = 0, uy = 0;          // unit xy direction a -> b
  double L = 0;                   // xy length (0: vertical edge)
  double inv_L = 0;               // 1 / L
  double sin_slope = 0;           // dz / |b - a|: where a ball touches along the edge
  double zmax = 0;                // max(a.z, b.z)
  double xmin = 0, xmax = 0, ymin = 0, ymax = 0;  // xy bounds of the segment
};
EdgeGeom make_edge(const geometry::Vec3& a, const geometry::Vec3& b);

// Drop height of the cutter at (x, y) against the closed segment; kNoContact
// if no point of it lies within R, or (for speed) if a bound shows the
// result cannot exceed `current`.
double edge_drop(const EdgeGeom& e, const CutterShape& cutter, double x, double y, double current = kNoContact);
// The same where it can exceed `current`; kNoContact where a cheap bound
// (top of the edge minus the profile height at its nearest point) shows it
// cannot.
inline double edge_drop_above(const EdgeGeom& e, const CutterShape& c, double x, double y, double current) {
  const double px = x - e.ax, py = y - e.ay;
  const double d = px * e.uy - py * e.ux;
  const double s0 = px * e.ux + py * e.uy;
  const double out = std::max(0.0, std::max(-s0, s0 - e.L));
  const double rho2 = e.L > 0 ? d * d + out * out : px * px + py * py;
  if (rho2 > c.R * c.R || !profile_below(c, rho2, e.zmax - current)) return kNoContact;
  return edge_drop(e, c, x, y, current);
}

inline double vertex_drop(const geometry::Vec3& v, const CutterShape& cutter, double x, double y) {
  const double ddx = v.x - x, ddy = v.y - y;
  const double rho2 = ddx * ddx + ddy * ddy;
  if (rho2 > cutter.R * cutter.R) return kNoContact;
  return v.z - cutter.h(std::sqrt(rho2));
}

inline double vertex_drop_above(const geometry::Vec3& v, const CutterShape& cutter, double x, double y, double current) {
  const double ddx = v.x - x, ddy = v.y - y;
  const double rho2 = ddx * ddx + ddy * ddy;
  if (rho2 > cutter.R * cutter.R || !profile_below(cutter, rho2, v.z - current)) return kNoContact;
  return v.z - cutter.h(std::sqrt(rho2));
}

// Lower bound (exact unless the segment's line crosses the rectangle) on the
// XY distance between the rectangle [x0, x1] x [y0, y1] and the segment
// (used to cull whole super-blocks of nodes).
double rect_segment_distance(const EdgeGeom& e, double x0, double y0, double x1, double y1);
// Cheaper, looser: distance from the centre minus the half diagonal.
inline double rect_segment_distance_lb(const EdgeGeom& e, double x0, double y0, double x1, double y1) {
  const double px = 0.5 * (x0 + x1) - e.ax, py = 0.5 * (y0 + y1) - e.ay;
  const double s = std::clamp(px * e.ux + py * e.uy, 0.0, e.L);  // L = 0: the point
  const double qx = px - s * e.ux, qy = py - s * e.uy;
  const double half_diag = 0.5 * std::sqrt((x1 - x0) * (x1 - x0) + (y1 - y0) * (y1 - y0));
  return std::max(0.0, std::sqrt(qx * qx + qy * qy) - half_diag);
}

}  // namespace cncstream::cam::cl_detail
