#pragma once
// How deep a pass cuts into a height-field stock: the pass machined into it
// (path_machining.hpp) move by move by the cutter less a rim, and each
// move's largest drop of a node. Left out, the rim: the skin an earlier
// roughing left along a wall, its thickness wide and as tall as the wall,
// which the cutter's side takes in one move - not a depth of cut. Not the
// tip alone: beside a tip the cutter meets material standing higher than
// at the tip's XY (where a narrow gap ends), and that is a depth of cut
// too. What the rim leaves standing is cut again by the next moves, so a
// depth is never less than the whole cutter's would be, less the rim.
// Used by the job to check a finishing pass against the stock the
// roughing leaves.
#include <vector>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/cam/path_machining.hpp"
#include "cncstream/cam/raster.hpp"
#include "cncstream/cam/stock.hpp"

namespace cncstream::cam {

// The stock's height at (x, y), bilinear between its nodes; NaN beyond its
// grid (no stock there).
double stock_height_at(const HeightFieldStock& stock, double x, double y);

struct PassDepth {
  double deepest = 0;  // mm: the deepest move's depth
  geometry::Vec3 at;             // its lower end (the tip)
  // Along the moves deeper than the limit, points a third of the radius
  // apart, each at the move's lower end's z.
  std::vector<geometry::Vec3> over;
  std::vector<MoveCut> too_deep;  // those moves
  double deepest_within = 0;      // the deepest of the other moves
};

// `pieces` are cut apart: the tool comes down from `retract_z` (above the
// stock) to each one's first point, and goes back up at its end, as the
// program does (its plunges are moves too). Throws std::invalid_argument for a rim that leaves no
// cutter, and as machine_path.
PassDepth pass_depth(const HeightFieldStock& stock, const std::vector<Polyline>& pieces, const Cutter& cutter,
                     double rim, double limit, double retract_z);

// The same pass against a stock nowhere higher than the one `before` was
// measured on (a further roughing cut into it), bounded without machining
// it again: a move's depth of cut only shrinks with the stock under it
// (every node after any moves is no higher), so the moves within the limit
// before stay within it, and a move too deep before is bounded by its cut
// alone into `lower` (what the moves before it take can only make it
// shallower). Exact for none of them; `over` lists the moves still over.
PassDepth pass_depth_bound(const HeightFieldStock& lower, const PassDepth& before, const Cutter& cutter, double rim,
                           double limit);

}  // namespace cncstream::cam
