#pragma once
// How far a program moves the tool on each axis, as the interpreter sees it:
// max − min of the positions its moves go to (arcs chorded like the
// firmware). Only differences matter, so the work offsets the controller
// holds (unknown here) cancel out. Left out, so that the extent is never
// larger than the program's real one: targets not relative to the work (G53
// machine coordinates, G28/G30 stored positions, a probe's search limit),
// and an axis's positions from such a move until the program sets that axis
// absolutely again (the start position counts only once the program has
// moved the axis to a known place). A change of coordinate system (G54..G59,
// whose offsets differ by unknown amounts) starts a new measure; the largest
// counts.
#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "cncstream/gcode/xy_hull.hpp"

namespace cncstream::gcode {

struct AxisExtent {
  double lo = 0, hi = 0;   // machine coordinates as traced from a zero start
  bool known = false;      // some move set this axis
  double size() const { return known ? hi - lo : 0; }
};

struct ProgramExtent {
  std::array<AxisExtent, 3> axes;  // X, Y, Z
  // The convex hull (counter-clockwise) of the XY positions where both X and
  // Y are known, in the frame the X measure comes from; fewer than 3
  // vertices when the program moves along a line.
  std::vector<XyPoint> xy_hull;
};

// Lines are raw program lines (comments, '%' and '$' lines allowed); lines
// the interpreter rejects are skipped.
ProgramExtent program_extent(const std::vector<std::string>& lines, double arc_tolerance = 0.002);

}  // namespace cncstream::gcode
