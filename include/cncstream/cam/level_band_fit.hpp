#pragma once
// Level runs (a waterline at one height, the part on its right, the free
// side on its left) reduced to fewer moves that never pass right of any of
// the run's points (no cut into the part) and at most `tolerance` left of
// them (bounded material left). The 2-D form of fit_profile_in_band: a
// vertex may sit anywhere from its point to `tolerance` left of it, so where
// the run curves round the part (an outside corner: every chord between its
// points cuts in) the moves circumscribe it, sqrt(8 R T) long for a radius
// R, instead of keeping every point.
#include <functional>
#include <optional>

#include "cncstream/cam/raster.hpp"

namespace cncstream::cam {

// Stretches of equal z are fitted separately, their ends kept; a point of
// another height (lifted over the part) is kept as it is. The first and the
// last point are kept exactly. With a lattice, vertices are put on it where
// a lattice point keeps the move in the band. Left of the run is free only
// near it: where the free side narrows to a slot, a vertex moved left can
// meet the slot's other wall. `clear` (the exact CL along a move, at or
// below the level) is asked of every move with a moved vertex; where none
// is clear the run keeps its own points there.
using LevelMoveCheck = std::function<bool(const geometry::Vec3& from, const geometry::Vec3& to)>;
Polyline fit_level_run_in_band(const Polyline& run, double tolerance,
                               const std::optional<XYLattice>& lattice = std::nullopt,
                               const LevelMoveCheck& clear = {});

}  // namespace cncstream::cam
