#include "cncsim/probe_targets.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "cncsim/number_text.hpp"

namespace cncsim {

using cncstream::Vec3;

namespace {

constexpr double kPlateSide = 40.0;   // a common touch plate's size, mm
constexpr double kSensorSide = 10.0;  // a tool-length sensor's button, mm
constexpr double kProbeFaceEps = 1e-9;

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

}  // namespace

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

bool ProbeTargets::triggered(const Vec3& tip) const {
  return std::any_of(faces_.begin(), faces_.end(),
                     [&](const ProbeFace& f) { return f.covers(tip.x, tip.y) && tip.z <= f.top + kProbeFaceEps; });
}

std::optional<double> ProbeTargets::first_change(const Vec3& a, const Vec3& b, bool to_state) const {
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
