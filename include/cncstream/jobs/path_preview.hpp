#pragma once
// A program's path thinned for drawing: at most a given number of points,
// cutting polylines and rapids apart, in work coordinates. The points kept
// are the ones that matter most to the shape (Douglas-Peucker order), and
// where a cut turns into a rapid before any others; the path's first and last
// points are always kept.
#include <cstddef>
#include <vector>

#include "cncstream/gcode/program.hpp"
#include "cncstream/geometry/vec3.hpp"

namespace cncstream::jobs {

struct PathPreview {
  std::vector<std::vector<geometry::Vec3>> cuts;    // feed moves, in program order
  std::vector<std::vector<geometry::Vec3>> rapids;  // G0 moves, in program order
  std::size_t points = 0;                 // in cuts and rapids together (a point shared by both counts twice)
  std::size_t total_points = 0;           // the program's path: where it starts and every move's end
};

// max_points >= 2 (std::invalid_argument otherwise). A span between two kept
// points is drawn as a cut when any move in it cuts, as a rapid when all are
// rapids, and not at all across a jump of the work offset (G92, G10 L20).
PathPreview decimate_path(const gcode::ProgramTrace& trace, std::size_t max_points);

}  // namespace cncstream::jobs
