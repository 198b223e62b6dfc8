#pragma once
// A roughing stock whose top is a height map (an earlier operation's
// result): where on the roughing grid there is material above a level, and
// how far each node is from it. Internal to the roughing.
#include <vector>

#include "cncstream/cam/cl_grid.hpp"
#include "cncstream/cam/zlevel_roughing.hpp"

namespace cncstream::cam::detail {

// Per node of `g`: the highest stock top within a cell of the node (the
// block's top where the surface does not reach; lowest() outside the block), so
// material between nodes is never missed.
std::vector<double> stock_top_on_grid(const GridSpec& g, const StockBlock& stock);

// Per node: distance to the nearest node with stock more than `above` above
// z, minus `reach` (<= 0: within reach of material above z).
std::vector<double> material_reach(const GridSpec& g, const std::vector<double>& top, double z, double above,
                                   double reach);

// Bilinear interpolation of node values at (x, y) (clamped to the grid).
double interpolate(const GridSpec& g, const std::vector<double>& v, double x, double y);

}  // namespace cncstream::cam::detail
