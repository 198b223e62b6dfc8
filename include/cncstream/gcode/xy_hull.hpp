#pragma once
// The convex hull of a program's XY positions: the outline the operator
// watches traced over the stock before cutting (protocol/outline_trace.hpp).
#include <array>
#include <cstddef>
#include <vector>

namespace cncstream::gcode {

using XyPoint = std::array<double, 2>;

// Counter-clockwise, no repeated or collinear vertices, starting at the
// lowest-left point. Fewer than 3 vertices when the points are all on a
// line (or fewer than 3 distinct).
std::vector<XyPoint> convex_hull(std::vector<XyPoint> points);

// The hull with its near-collinear vertices dropped, so an arc's hundreds of
// chords trace as a few segments: every dropped vertex lies within
// `tolerance` of the chord that replaces it (the result runs inside the hull
// by at most that). Starts at the sharpest corner; fewer than 3 vertices
// left (a huge tolerance) returns the hull unchanged.
std::vector<XyPoint> simplify_hull(std::vector<XyPoint> hull, double tolerance);

// Collects points for a hull without holding a program's millions of
// positions: past `limit` points the buffer is replaced by its hull.
class HullAccumulator {
 public:
  explicit HullAccumulator(std::size_t limit = 1 << 16) : limit_(limit) {}
  void add(double x, double y);
  std::vector<XyPoint> hull() const { return convex_hull(points_); }
  bool empty() const { return points_.empty(); }

 private:
  std::size_t limit_;
  std::vector<XyPoint> points_;
};

}  // namespace cncstream::gcode
