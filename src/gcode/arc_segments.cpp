#include "cncstream/gcode/arc_segments.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace cncstream::gcode {
namespace {

constexpr double kAngularTravelEpsilon = 5e-7;  // GRBL ARC_ANGULAR_TRAVEL_EPSILON
constexpr double kMaxArcSegments = 65535;       // GRBL's segment counter is a uint16_t

}  // namespace

double arc_angular_travel(const ArcMove& arc) {
  const PlaneAxes ax = axes_of(arc.plane);
  const double r0 = component(arc.from, ax.first) - component(arc.center, ax.first);
  const double r1 = component(arc.from, ax.second) - component(arc.center, ax.second);
  const double t0 = component(arc.to, ax.first) - component(arc.center, ax.first);
  const double t1 = component(arc.to, ax.second) - component(arc.center, ax.second);
  double travel = std::atan2(r0 * t1 - r1 * t0, r0 * t0 + r1 * t1);
  if (arc.clockwise) {
    if (travel >= -kAngularTravelEpsilon) travel -= 2 * std::numbers::pi;
  } else {
    if (travel <= kAngularTravelEpsilon) travel += 2 * std::numbers::pi;
  }
  return travel;
}

std::vector<geometry::Vec3> segment_arc(const ArcMove& arc, double tolerance) {
  const PlaneAxes ax = axes_of(arc.plane);
  const double travel = arc_angular_travel(arc);
  const double r = arc.radius;
  std::size_t segments = 0;
  if (r > 0 && tolerance > 0 && tolerance < 2 * r) {
    // GRBL counts an arc's segments in a uint16_t; a count beyond it (a radius
    // of kilometres) or not a number must not become a size_t (undefined
    // behaviour) nor an allocation of that many points.
    const double n = std::floor(std::fabs(0.5 * travel * r) / std::sqrt(tolerance * (2 * r - tolerance)));
    if (n >= 0) segments = static_cast<std::size_t>(std::min(n, kMaxArcSegments));
  }
  std::vector<geometry::Vec3> points;
  points.reserve(segments + 1);
  const double c0 = component(arc.center, ax.first), c1 = component(arc.center, ax.second);
  const double start_angle = std::atan2(component(arc.from, ax.second) - c1, component(arc.from, ax.first) - c0);
  const double start_radius = std::hypot(component(arc.from, ax.first) - c0, component(arc.from, ax.second) - c1);
  const double lin0 = component(arc.from, ax.normal);
  const double lin_travel = component(arc.to, ax.normal) - lin0;
  for (std::size_t i = 1; i < segments; ++i) {
    const double f = static_cast<double>(i) / static_cast<double>(segments);
    const double a = start_angle + travel * f;
    geometry::Vec3 p;
    component(p, ax.first) = c0 + start_radius * std::cos(a);
    component(p, ax.second) = c1 + start_radius * std::sin(a);
    component(p, ax.normal) = lin0 + lin_travel * f;
    points.push_back(p);
  }
  points.push_back(arc.to);
  return points;
}

ArcChords arc_chords(const ArcMove& arc, double arc_tolerance) {
  ArcChords c{segment_arc(arc, arc_tolerance), arc.feed};
  if (arc.inverse_time) {
    double length = 0;
    geometry::Vec3 p = arc.from;
    for (const geometry::Vec3& q : c.points) {
      length += norm(q - p);
      p = q;
    }
    c.feed = arc.feed * length;
  }
  return c;
}

}  // namespace cncstream::gcode
