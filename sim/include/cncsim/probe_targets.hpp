#pragma once
// What the simulated probe input touches: a touch plate lying on the work, a
// fixed tool-length sensor, or (the old --probe-z) a plane everywhere. Each is
// a level top face over an XY rectangle in machine coordinates; the input is
// active while the tool's TIP is at or below a face within its rectangle.
// Geometry only: the machine decides what a contact means (GRBL's G38.x).
#include <optional>
#include <string>
#include <vector>

#include "cncstream/geometry/vec3.hpp"

namespace cncsim {

struct ProbeFace {
  std::string name;        // "touch plate", "tool sensor", "probe plane"
  double x0 = 0, y0 = 0;   // XY rectangle (machine mm); x0 > x1 means unbounded
  double x1 = 0, y1 = 0;
  double top = 0;          // the face's height (machine mm)
  bool everywhere = false; // a plane (no rectangle)
  bool covers(double x, double y) const {
    return everywhere || (x >= x0 && x <= x1 && y >= y0 && y <= y1);
  }
};

// "X,Y,THICKNESS": a 40 mm square plate centred on X,Y (machine mm) lying on
// a surface at `surface_z`. Throws std::invalid_argument naming the text.
ProbeFace parse_touch_plate(const std::string& text, double surface_z);
// "X,Y,Z": a 10 mm square sensor button centred on X,Y, its top at Z (machine mm).
ProbeFace parse_tool_sensor(const std::string& text);

class ProbeTargets {
 public:
  void add(ProbeFace f) { faces_.push_back(std::move(f)); }
  bool empty() const { return faces_.empty(); }
  const std::vector<ProbeFace>& faces() const { return faces_; }
  // Whether the probe input is active with the tip at `tip`.
  bool triggered(const cncstream::Vec3& tip) const;
  // Along the straight tip move a -> b: the fraction (0..1] where the input
  // first changes to `to_state` (true: touches, false: lets go); nullopt when
  // it never does within the move.
  std::optional<double> first_change(const cncstream::Vec3& a, const cncstream::Vec3& b, bool to_state) const;

 private:
  std::vector<ProbeFace> faces_;
};

}  // namespace cncsim
