#include "cncsim/probe_targets.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "cncsim/number_text.hpp"

namespace cncsim {

using cncstream::geometry::Vec3;

namespace {

constexpr double kPlateSide = 40.0;   // a common touch plate's size, mm
constexpr double kSensorSide = 10.0;  // a tool-length sensor's button, mm
constexpr double kProbeFaceEps = 1e-9;
constexpr double kCornerPlateSide = 50.0;  // a corner plate's top, from its outer walls, mm
// A move is sampled this finely for the first contact of a cutter with a
// radius (then bisected): a target thinner than this could be missed.
constexpr double kContactSampleMm = 0.01;

ProbeFace probe_face_square(std::string name, double x, double y, double side, double top) {
  ProbeFace f;
  f.name = std::move(name);
  f.x0 = x - side / 2;
  f.x1 = x + side / 2;
  f.y0 = y - side / 2;
  f.y1 = y + side / 2;
  f.top = top;
  return f;
}

// The cutter's horizontal reach at `h` above its tip (negative below the tip).
double cutter_reach_at(const cncstream::cam::Cutter& c, double h) {
  if (h < -kProbeFaceEps) return -1;
  const double rk = c.corner_radius;
  if (h >= rk) return c.radius;
  const double d = rk - std::max(h, 0.0);
  return c.core_radius() + std::sqrt(std::max(0.0, rk * rk - d * d));
}

bool face_touched(const ProbeFace& f, const Vec3& tip, const ProbeTool& tool) {
  if (!tool) return f.covers(tip.x, tip.y) && tip.z <= f.top + kProbeFaceEps;
  if (tip.z > f.top + kProbeFaceEps) return false;
  if (f.everywhere) return true;
  const double dx = std::max({f.x0 - tip.x, 0.0, tip.x - f.x1});
  const double dy = std::max({f.y0 - tip.y, 0.0, tip.y - f.y1});
  return std::hypot(dx, dy) <= cutter_reach_at(*tool, f.top - tip.z) + kProbeFaceEps;
}

}  // namespace

ProbeFace parse_corner_plate(const std::string& text, double corner_x, double corner_y, double stock_top) {
  std::vector<double> v;
  std::size_t start = 0;
  bool bad = false;
  while (start <= text.size()) {
    const auto comma = text.find(',', start);
    const auto n = number_from<double>(std::string_view(text).substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (!n) bad = true;
    else v.push_back(*n);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (bad || v.size() < 2 || v.size() > 3 || !(v[0] > 0) || !(v[1] >= 0) || (v.size() == 3 && !(v[2] > v[1])))
    throw std::invalid_argument("--corner-plate '" + text +
                                "': expected THICKNESS,LIP[,SIZE] (mm: thickness > 0, lip >= 0, size > lip)");
  const double lip = v[1], side = v.size() == 3 ? v[2] : kCornerPlateSide;
  ProbeFace f;
  f.name = "corner plate";
  f.x0 = corner_x - lip;
  f.y0 = corner_y - lip;
  f.x1 = f.x0 + side;
  f.y1 = f.y0 + side;
  f.top = stock_top + v[0];
  return f;
}

ProbeFace parse_touch_plate(const std::string& text, double surface_z) {
  const auto v = vec3_from(text);
  if (!v || !(v->z > 0))
    throw std::invalid_argument("--touch-plate '" + text + "': expected X,Y,THICKNESS (machine mm, thickness > 0)");
  return probe_face_square("touch plate", v->x, v->y, kPlateSide, surface_z + v->z);
}

ProbeFace parse_tool_sensor(const std::string& text) {
  const auto v = vec3_from(text);
  if (!v) throw std::invalid_argument("--tool-sensor '" + text + "': expected X,Y,Z (its top, machine mm)");
  return probe_face_square("tool sensor", v->x, v->y, kSensorSide, v->z);
}

bool ProbeTargets::triggered(const Vec3& tip, const ProbeTool& tool) const {
  return std::any_of(faces_.begin(), faces_.end(), [&](const ProbeFace& f) { return face_touched(f, tip, tool); });
}

std::optional<double> ProbeTargets::first_change(const Vec3& a, const Vec3& b, bool to_state,
                                                 const ProbeTool& tool) const {
  if (tool) {
    // A round flank's contact has no simple crossing: sample, then bisect
    // the first step whose end is in the state sought.
    const Vec3 d = b - a;
    const double length = norm(d);
    const auto steps = static_cast<std::size_t>(std::ceil(length / kContactSampleMm)) + 1;
    double before = 0;
    for (std::size_t i = 1; i <= steps; ++i) {
      const double t = static_cast<double>(i) / static_cast<double>(steps);
      if (triggered(a + d * t, tool) != to_state) {
        before = t;
        continue;
      }
      double lo = before, hi = t;
      for (int k = 0; k < 60; ++k) {
        const double mid = 0.5 * (lo + hi);
        (triggered(a + d * mid, tool) == to_state ? hi : lo) = mid;
      }
      return hi;
    }
    return std::nullopt;
  }
  // The input changes where the tip crosses a face's height inside its
  // rectangle, or enters/leaves the rectangle below the height. Candidate
  // fractions are checked in order; the first whose state differs wins.
  std::vector<double> ts;
  const Vec3 d = b - a;
  for (const ProbeFace& f : faces_) {
    if (std::fabs(d.z) > kProbeFaceEps) ts.push_back((f.top - a.z) / d.z);
    if (f.everywhere) continue;
    if (std::fabs(d.x) > kProbeFaceEps) {
      ts.push_back((f.x0 - a.x) / d.x);
      ts.push_back((f.x1 - a.x) / d.x);
    }
    if (std::fabs(d.y) > kProbeFaceEps) {
      ts.push_back((f.y0 - a.y) / d.y);
      ts.push_back((f.y1 - a.y) / d.y);
    }
  }
  std::sort(ts.begin(), ts.end());
  for (double t : ts) {
    if (!(t > kProbeFaceEps) || t > 1 + kProbeFaceEps) continue;
    const double tc = std::min(t, 1.0);
    // Just past the crossing, so a face's edge counts as reached.
    const Vec3 p = a + d * std::min(1.0, tc + 1e-9);
    const Vec3 at = a + d * tc;
    if (triggered(at) == to_state || triggered(p) == to_state) return tc;
  }
  return std::nullopt;
}

}  // namespace cncsim
