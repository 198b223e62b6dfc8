#pragma once
// Machines a tool-tip path into a height-field stock with the simulator's own
// material removal (HeightFieldStock), split into horizontal bands cut in
// parallel (oneTBB tasks): each band is its own stock at the whole grid's node
// coordinates and takes, in order, the moves that can reach it, so the result
// equals one stock cut move by move, bit for bit, however the bands ran.
#include <vector>

#include "cncstream/cam/checkpoint.hpp"
#include "cncstream/cam/cl_grid.hpp"
#include "cncstream/cam/cutter.hpp"
#include "cncstream/cam/raster.hpp"

namespace cncstream::cam {

// `pieces` are cut in order; consecutive pieces are joined by a straight move
// from one's last point to the next's first (as in a raster: row, link,
// row...). `heights` (grid.size() values) is the stock before; returns it after.
// Runs in the caller's oneTBB task arena (a job limits it with
// run_with_thread_limit). `checkpoint` is called as bands are done (see
// checkpoint.hpp).
std::vector<double> machine_path(const GridSpec& grid, std::vector<double> heights, const std::vector<Polyline>& pieces,
                                 const Cutter& cutter, const Checkpoint& checkpoint = {});

// A move of a path that cut, and its depth of cut: the largest height drop
// of a stock node in it (HeightFieldStock::last_max_depth, over all bands).
struct MoveCut {
  geometry::Vec3 a, b;
  double depth = 0;
};

// As machine_path, and every move that cut into `cuts` (in cutting order).
std::vector<double> machine_path(const GridSpec& grid, std::vector<double> heights, const std::vector<Polyline>& pieces,
                                 const Cutter& cutter, std::vector<MoveCut>& cuts, const Checkpoint& checkpoint = {});

// A raster's pieces in cutting order: row 0, link 0, row 1, ...
std::vector<Polyline> raster_pieces(const RasterPath& path);

}  // namespace cncstream::cam
