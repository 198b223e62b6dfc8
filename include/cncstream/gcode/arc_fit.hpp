#pragma once
// Replaces runs of a tool-tip polyline by circular arcs (G2/G3) where the
// arc, as the controller will cut it, stays within a tolerance of every point
// it replaces. GRBL cuts an arc as chords (mc_arc): floor(length / nominal
// chord) of them, the nominal chord sagging its arc tolerance ($12) inside the
// circle, so a short arc's few chords sag more. The fit checks every point
// against the circle and against those chords exactly (for the chord count
// GRBL computes and one more or fewer, its float arithmetic allowing).
//
// Arcs are planar: G17 for a run of constant Z, G18 for a run of constant Y,
// G19 for a run of constant X. Sweeps stay below half a turn, so a centre
// offset (I/J/K) always names one arc and the direction follows from the side
// the points bulge to. Centres are rounded to `center_step` before the final
// check, so the written offsets are the ones checked, and GRBL's radius check
// (error 33: 0.005 mm and 0.1 %) is met with a wide margin (at most 0.001 mm).
#include <cstddef>
#include <vector>

#include "cncstream/gcode/interpreter.hpp"
#include "cncstream/geometry/vec3.hpp"

namespace cncstream {

struct ArcFitOptions {
  double tolerance = 0.01;                  // mm: allowed deviation of the cut path (chords included)
  double controller_arc_tolerance = 0.002;  // mm: GRBL $12 (0: the controller cuts exact arcs)
  double max_radius = 1000;                 // mm: flatter runs stay lines (and GRBL's floats stay exact)
  double min_sweep = 1e-3;                  // rad: shorter turns stay lines
  double center_step = 1e-4;                // mm: resolution of the written I/J/K
  std::size_t min_segments = 3;             // an arc replaces at least this many segments
  // One-sided, for paths over material below them (a raster row's CL
  // profile): arcs only in G18/G19, every replaced point and segment on or
  // below the cut path (never a gouge) and at most `tolerance` below it.
  // Without it: two-sided, every replaced point within `tolerance` of the path.
  bool material_below = false;
  // One-sided, for level paths beside material on their right (a waterline
  // climb-milling around a part with a clockwise spindle): arcs in G17 only
  // are made one-sided, the controller's cut (arc and chords) never crossing
  // a replaced point or segment towards the right and at most `tolerance`
  // from them to the left. Runs in G18/G19 follow material_below (or are
  // two-sided without it).
  bool material_right = false;
  // Long stretches fitted in chunks on several threads, stitched into the
  // serial fit's moves exactly (false: one thread, for comparison).
  bool parallel = true;
};

struct FittedMove {
  bool arc = false;  // false: a straight feed move to `to`
  geometry::Vec3 to;
  // Arcs only: plane, direction as G2 (clockwise) or G3 sees it in that plane,
  // and the centre offset from the move's start (I, J, K; zero off the plane).
  gcode::Plane plane = gcode::Plane::XY;
  bool clockwise = false;
  geometry::Vec3 center_offset;
  double radius = 0;  // from the start point to the (rounded) centre
  double sweep = 0;   // rad, positive
};

// `points`: the polyline, first point excluded from the output (it is where
// the cut starts). The moves end exactly at the input points they keep; the
// last one ends at the last point. Throws std::invalid_argument for bad
// options.
std::vector<FittedMove> fit_arcs(const std::vector<geometry::Vec3>& points, const ArcFitOptions& options);

}  // namespace cncstream
