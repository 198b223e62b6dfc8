#pragma once
// Exact Euclidean distance transform of a mask on a regular grid
// (Felzenszwalb and Huttenlocher's lower envelope of parabolas, one pass per
// axis): for every node, the distance in mm to the nearest node outside the
// mask. Nodes beyond the grid count as outside (so distances never exceed
// the distance to the nearest node past the border) unless
// `beyond_is_outside` is false; then a grid without an outside node is all
// +infinity.
#include <cstdint>
#include <vector>

#include "cncstream/cam/cl_grid.hpp"

namespace cncstream::cam {

// `inside`: grid.size() flags (1 = in the mask). Outside nodes get 0.
// Throws std::invalid_argument if the sizes differ.
std::vector<double> distance_to_outside(const GridSpec& grid, const std::vector<std::uint8_t>& inside,
                                        bool beyond_is_outside = true);

}  // namespace cncstream::cam
