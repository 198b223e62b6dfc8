#pragma once
// A pass of a tool path: tool-tip points, cut in order.
#include <cmath>
#include <vector>

#include "cncstream/geometry/vec3.hpp"

namespace cncstream::cam {

using Polyline = std::vector<geometry::Vec3>;

// Distance seen from above (what a level pass covers).
inline double xy_dist(const geometry::Vec3& a, const geometry::Vec3& b) { return std::hypot(b.x - a.x, b.y - a.y); }

}  // namespace cncstream::cam
