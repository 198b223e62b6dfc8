#pragma once
// The oracle's view of a cutter (cl_oracle::Tool), written from each shape's
// geometry and sharing no code with the engine or Cutter::profile(): flat,
// ball and bull-nose by their radii; a V-bit as a cone of half-angle a above
// its flat tip, h = (rho - rt) / tan(a); a tapered ball-nose as a ball of
// radius r up to where a cone of half-angle a is tangent to it (rho = r cos a)
// and that cone beyond.
#include <cmath>
#include <stdexcept>

#include "cam/cl_oracle.hpp"
#include "cncstream/cam/cutter.hpp"

namespace cl_oracle {

inline double vbit_height(double half_angle_deg, double tip_radius, double rho) {
  const double a = half_angle_deg * std::acos(-1.0) / 180;
  return rho <= tip_radius ? 0.0 : (rho - tip_radius) * std::cos(a) / std::sin(a);
}

inline double tapered_ball_height(double ball_radius, double half_angle_deg, double rho) {
  const double a = half_angle_deg * std::acos(-1.0) / 180, r = ball_radius;
  // Tangent point: the ball's normal there is perpendicular to the cone's side.
  const double rt = r * std::cos(a);
  if (rho <= rt) return r - std::sqrt(std::max(0.0, r * r - rho * rho));
  return r - r * std::sin(a) + (rho - rt) / std::tan(a);
}

inline Tool tool_of(const cncstream::cam::Cutter& c) {
  using cncstream::cam::CutterType;
  if (c.grown != 0) throw std::invalid_argument("tool_of: grown cutters have no closed form here");
  switch (c.type) {
    case CutterType::Flat: return {c.radius, 0.0};
    case CutterType::Ball: return {c.radius, c.radius};
    case CutterType::Bull: return {c.radius, c.corner_radius};
    case CutterType::VBit: {
      const double a = c.half_angle_deg, rt = c.tip_radius;
      return {c.radius, 0.0, [a, rt](double rho) { return vbit_height(a, rt, rho); }};
    }
    case CutterType::TaperedBall: {
      const double a = c.half_angle_deg, r = c.corner_radius;
      return {c.radius, r, [a, r](double rho) { return tapered_ball_height(r, a, rho); }};
    }
  }
  throw std::invalid_argument("tool_of: unknown cutter");
}

}  // namespace cl_oracle
