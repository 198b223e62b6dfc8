#pragma once
// Arc to chord segmentation the way GRBL's mc_arc does it: the number of
// chords keeps the chord error within the arc tolerance ($12), and a
// start == end arc in centre format is a full circle.
#include <vector>

#include "cncstream/gcode/interpreter.hpp"

namespace cncstream::gcode {

// A plane's two axes in the order G2/G3 measure turns (G17: X then Y, G18: Z
// then X, G19: Y then Z; 0 = X, 1 = Y, 2 = Z), and the axis normal to it.
// Counter-clockwise in (first, second) is G3 in all three: seen from the
// normal's positive side.
struct PlaneAxes {
  int first, second, normal;
};
constexpr PlaneAxes axes_of(Plane p) {
  switch (p) {
    case Plane::XY: return {0, 1, 2};
    case Plane::ZX: return {2, 0, 1};
    default: return {1, 2, 0};
  }
}

// Signed angular travel (radians, negative = clockwise) of an arc.
double arc_angular_travel(const ArcMove& arc);

// The chord end points, the last one exactly arc.to. Never empty.
std::vector<geometry::Vec3> segment_arc(const ArcMove& arc, double arc_tolerance);

// An arc as the straight moves that run it: its chords (segment_arc) and the
// feed every chord runs at, mm/min. In inverse time (G93) the whole arc takes
// 1/F minutes, so the feed is F times the chords' length.
struct ArcChords {
  std::vector<geometry::Vec3> points;  // chord end points, from segment_arc
  double feed = 0;
};
ArcChords arc_chords(const ArcMove& arc, double arc_tolerance);

}  // namespace cncstream::gcode
