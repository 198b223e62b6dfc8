#pragma once
// Steep and shallow: the raster cuts where the surface is gentle and the
// waterline (waterline.hpp) where it is steep. The raster's steep stretches
// are left out by bridges: a stretch of a row whose every point, and every
// point along its moves half a slope-map cell apart, lies where the surface
// is at least `angle` steep is replaced by a move up to its highest point,
// across, and down (judged along the moves too: a merged row's long move
// over level ground between two walls is no steep stretch). The raster's own polyline is on or above
// the CL everywhere (its chords were checked), so a level move along the
// same row at the height of its highest point is too: a bridge never gouges.
#include <cstddef>
#include <vector>

#include "cncstream/cam/raster.hpp"
#include "cncstream/cam/slope_map.hpp"

namespace cncstream::cam {

struct SteepSkip {
  std::vector<Polyline> pieces;
  std::size_t bridges = 0;
  std::size_t points_skipped = 0;
};

// `angle` in radians. Only stretches along one row (one X or one Y for all
// their points and the points beside them) are bridged.
SteepSkip skip_steep(const std::vector<Polyline>& pieces, const SlopeMap& slope, double angle);

}  // namespace cncstream::cam
