#pragma once
// The lower envelope of a generalized APT cutter swept along a straight tip
// path (private to src/cam; stock.cpp runs it per node).
//
// For a point at horizontal offset from the path, write s for the tip's
// signed along-path distance past the point's foot on the path line, and e
// for the point's distance from that line. The cutter surface above the
// point is at
//     f(s) = z0 + m*s + h(sqrt(s^2 + e^2)),  s in [s_a, s_b], s^2 + e^2 <= R^2
// with m = dz per unit of horizontal travel and h the cutter profile. h is
// convex and non-decreasing and the distance is convex in s, so f is convex:
// its minimum is the clamped root of f'. Flat: an end of the interval. Ball:
// closed form s* = -m w / sqrt(1 + m^2), w = sqrt(R^2 - e^2). Bull-nose: a
// safeguarded Newton iteration on f' (monotone), bracketed by the flat core.
// Any other profile (V-bit, tapered ball): mirrored, this is the CL
// engine's edge contact (the line's maximiser of -m s - h), band by band.
#include <algorithm>
#include <cmath>
#include <limits>

#include "cl_contact.hpp"
#include "cncstream/cam/cutter.hpp"
#include "cncstream/geometry/vec3.hpp"

namespace cncstream::cam::detail {

class SweptCutter {
 public:
  enum class Shape { Flat, Ball, Bull, General };

  SweptCutter(const geometry::Vec3& a, const geometry::Vec3& b, const Cutter& c) : a_(a) {
    R_ = c.radius;
    rk_ = std::clamp(c.corner_radius, 0.0, R_);
    rc_ = R_ - rk_;
    shape_ = rk_ <= R_ * 1e-12 ? Shape::Flat : (rc_ <= R_ * 1e-12 ? Shape::Ball : Shape::Bull);
    if (shape_ == Shape::Ball) rc_ = 0, rk_ = R_;
    if (!c.is_apt()) {
      shape_ = Shape::General;
      prof_ = c.profile();
      R_ = prof_.R;
    }
    const double ddx = b.x - a.x, ddy = b.y - a.y, ddz = b.z - a.z;
    L_ = std::sqrt(ddx * ddx + ddy * ddy);
    vertical_ = L_ < 1e-9;
    if (!vertical_) {
      ux_ = ddx / L_;
      uy_ = ddy / L_;
      m_ = ddz / L_;
      k_ = ddz / std::sqrt(L_ * L_ + ddz * ddz);
    }
    zmin_ = std::min(a.z, b.z);
    level_ = std::fabs(ddz) <= 1e-12 * std::max(1.0, L_);
  }

  double radius() const { return R_; }
  double lowest_tip_z() const { return zmin_; }
  bool vertical() const { return vertical_; }
  double ux() const { return ux_; }
  double uy() const { return uy_; }
  double length() const { return L_; }
  const geometry::Vec3& start() const { return a_; }

  // Height of the cutter surface's profile at distance rho (rho <= R).
  double h(double rho) const {
    if (shape_ == Shape::General) return prof_.h(rho);
    const double q = rho - rc_;
    if (q <= 0) return 0;
    const double u = std::min(q, rk_);
    return rk_ - std::sqrt(std::max(0.0, rk_ * rk_ - u * u));
  }

  // Lowest height reached above (x, y); +inf if the cutter never covers it.
  double lowest_at(double x, double y) const {
    const double px = x - a_.x, py = y - a_.y;  // no ceiling: the exact value
    if (vertical_) return lowest_vertical(px * px + py * py);
    const double along = px * ux_ + py * uy_, perp = py * ux_ - px * uy_;
    return lowest(along, perp * perp);
  }

  // A plunge or pure Z move: the tip's xy is fixed; the lowest z wins.
  double lowest_vertical(double d2) const {
    if (d2 > R_ * R_) return kOut;
    return zmin_ + h(std::sqrt(d2));
  }

  // along: the point's foot on the path, measured from a; e2: squared
  // distance from the path line. Returns kOut early when the result cannot
  // go below `ceiling` (the node's current height).
  double lowest(double along, double e2, double ceiling = kOut) const {
    const double w2 = R_ * R_ - e2;
    if (w2 < 0) return kOut;
    const double sa = -along, sb = L_ - along;  // the tip's s at a and at b
    if (level_) {
      // Level move: the nearest tip position is lowest.
      const double s = std::clamp(0.0, sa, sb);
      const double d2 = s * s + e2;
      if (d2 > R_ * R_) return kOut;
      return a_.z + h(std::sqrt(d2));
    }
    const double w = std::sqrt(w2);
    const double lo = std::max(sa, -w), hi = std::min(sb, w);
    if (lo > hi) return kOut;
    const double z0 = a_.z + m_ * along;  // tip height when over the foot (s = 0)
    // The lowest tip height while in reach bounds the result from below.
    if (z0 + m_ * (m_ > 0 ? lo : hi) >= ceiling) return kOut;
    switch (shape_) {
      case Shape::Flat: return z0 + m_ * (m_ > 0 ? lo : hi);
      case Shape::Ball: {
        const double s = std::clamp(-k_ * w, lo, hi);
        return z0 + m_ * s + R_ - std::sqrt(std::max(0.0, w2 - s * s));
      }
      case Shape::Bull: {
        // Mirror so the tip rises with s (m > 0); the minimum then lies at
        // or before the flat core's near edge.
        const double m = std::fabs(m_);
        const double l = m_ > 0 ? lo : -hi, r = m_ > 0 ? hi : -lo;
        const double s = bull_argmin(m, e2, w, l, r);
        return z0 + m * s + h(std::sqrt(s * s + e2));
      }
      case Shape::General: {
        const double m = std::fabs(m_);
        const double l = m_ > 0 ? lo : -hi, r = m_ > 0 ? hi : -lo;
        const double s = std::clamp(-cl_detail::line_contact_offset(prof_, std::fabs(k_), std::sqrt(e2)), l, r);
        return z0 + m * s + h(std::sqrt(s * s + e2));
      }
    }
    return kOut;
  }

  static constexpr double kOut = std::numeric_limits<double>::infinity();

 private:
  // f'(s) / its derivative for the bull-nose, m > 0.
  double slope(double m, double s, double e2) const {
    const double d = std::sqrt(s * s + e2), q = d - rc_;
    if (q <= 0 || d <= 0) return m;
    const double c2 = rk_ * rk_ - q * q;
    if (c2 <= 0) return s < 0 ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
    return m + q / std::sqrt(c2) * s / d;
  }
  double curvature(double s, double e2) const {
    const double d = std::sqrt(s * s + e2), q = d - rc_;
    if (q <= 0 || d <= 0) return 0;
    const double c2 = rk_ * rk_ - q * q;
    if (c2 <= 0) return std::numeric_limits<double>::infinity();
    const double c = std::sqrt(c2);
    return rk_ * rk_ / (c2 * c) * (s * s) / (d * d) + q / c * e2 / (d * d * d);
  }

  // argmin over [l, r] of m*s + h(|(s, e)|), m > 0, convex.
  double bull_argmin(double m, double e2, double w, double l, double r) const {
    // Where the flat core ends on the near side: f' = m > 0 from there on.
    const double core = e2 < rc_ * rc_ ? -std::sqrt(rc_ * rc_ - e2) : 0.0;
    double hi = std::min(r, core);
    if (l >= hi) return l;
    if (slope(m, hi, e2) <= 0) return hi;
    double lo = std::max(l, -w);
    if (slope(m, lo, e2) >= 0) return lo;
    // Safeguarded Newton: keep the bracket [lo, hi] with f'(lo) < 0 < f'(hi).
    double s = 0.5 * (lo + hi);
    for (int it = 0; it < 100 && hi - lo > 1e-12 * (1 + R_); ++it) {
      const double g = slope(m, s, e2);
      if (g == 0) return s;
      (g < 0 ? lo : hi) = s;
      const double gp = curvature(s, e2);
      double next = (gp > 0 && std::isfinite(gp)) ? s - g / gp : 0.5 * (lo + hi);
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
      if (std::fabs(next - s) < 1e-13 * (1 + R_)) return next;
      s = next;
    }
    return s;
  }

  geometry::Vec3 a_;
  double R_ = 0, rk_ = 0, rc_ = 0;
  Shape shape_ = Shape::Ball;
  CutterProfile prof_;  // General
  double L_ = 0, ux_ = 1, uy_ = 0, m_ = 0, k_ = 0, zmin_ = 0;
  bool vertical_ = false, level_ = true;
};

}  // namespace cncstream::cam::detail
