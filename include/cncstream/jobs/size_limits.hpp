#pragma once
// Sizes beyond reason, refused before any work starts: a part far larger than
// a router (coordinates in the wrong unit), or a grid whose nodes would not
// fit in memory. Estimated from the sizes alone, before anything is allocated.
#include <cstddef>
#include <string>

#include "cncstream/geometry/mesh.hpp"
#include "cncstream/geometry/stl.hpp"

namespace cncstream::jobs {

// A part larger than this on any axis is refused (a few metres: a big router).
constexpr double kDefaultMaxPartMm = 3000;

// Throws std::invalid_argument naming `source`, the part's size and the
// likely cause (its units) when an extent exceeds `limit_mm`.
void check_part_size(const geometry::Box3& bounds, const std::string& source, double limit_mm = kDefaultMaxPartMm);

// A part whose size suggests it was read in the wrong units: smaller than
// the cutter, or a few millimetres when its numbers were probably metres or
// inches. Returns a warning naming the likely --units (and the size it would
// have), or "" when the size is plausible. `units`: what it was read in.
std::string units_warning(const geometry::Box3& bounds, geometry::LengthUnit units, double cutter_diameter, const std::string& source);

// Half of this machine's physical memory: what one job may plan to use.
std::size_t memory_budget_bytes();

// Throws std::invalid_argument when nx × ny nodes of `bytes_per_node` exceed
// `budget` (0: memory_budget_bytes()), naming `what`, the node count, the
// bytes and the step that makes them.
void check_grid_memory(double nx, double ny, double bytes_per_node, double step_mm, const std::string& what,
                       std::size_t budget = 0);

}  // namespace cncstream::jobs
