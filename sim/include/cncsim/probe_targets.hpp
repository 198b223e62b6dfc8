#pragma once
// What the simulated probe input touches: a touch plate lying on the work, a
// fixed tool-length sensor, a corner plate on the stock's corner, or (the old
// --probe-z) a plane everywhere. Each is a level top face over an XY
// rectangle in machine coordinates, solid below it (the tool comes from above:
// whatever of a target lies under its top, a plate's lip down the stock's
// side included, meets the cutter's flank first). The input is active while
// the cutter touches one: its tip at or below the top and its profile (its
// radius at the top's height above the tip) within reach of the rectangle, so
// a side probe trips where the flank meets a wall. Geometry only: the machine
// decides what a contact means (GRBL's G38.x).
#include <optional>
#include <string>
#include <vector>

#include "cncstream/cam/cutter.hpp"
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

// A corner touch plate on a stock's X-min/Y-min corner (the stock's corner at
// machine X,Y, its top at `stock_top`): a plate of THICKNESS on the top, SIZE
// square from its outer walls, with lips LIP thick down the stock's front
// (Y-min) and left (X-min) sides, so its outer walls stand LIP outside the
// stock's edges. "THICKNESS,LIP[,SIZE]" (SIZE 50 by default). Throws
// std::invalid_argument naming the text.
ProbeFace parse_corner_plate(const std::string& text, double corner_x, double corner_y, double stock_top);

// What touches: the cutter at the tip (nullopt: the tip as a point, the
// shape before tools had one).
using ProbeTool = std::optional<cncstream::cam::Cutter>;

class ProbeTargets {
 public:
  void add(ProbeFace f) { faces_.push_back(std::move(f)); }
  bool empty() const { return faces_.empty(); }
  const std::vector<ProbeFace>& faces() const { return faces_; }
  // Whether the probe input is active with the tip at `tip`.
  bool triggered(const cncstream::geometry::Vec3& tip, const ProbeTool& tool = std::nullopt) const;
  // Along the straight tip move a -> b: the fraction (0..1] where the input
  // first changes to `to_state` (true: touches, false: lets go); nullopt when
  // it never does within the move.
  std::optional<double> first_change(const cncstream::geometry::Vec3& a, const cncstream::geometry::Vec3& b, bool to_state,
                                     const ProbeTool& tool = std::nullopt) const;

 private:
  std::vector<ProbeFace> faces_;
};

}  // namespace cncsim
