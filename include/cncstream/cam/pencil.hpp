#pragma once
// Pencil passes: the cutter along the concave creases of its own CL surface
// (where two faces meet in a valley narrower than it: the bottom of a
// V-groove, an inside corner's crease), where it touches both faces at once.
// A row crossing such a crease leaves a cusp between rows right at it; one
// pass along it takes the crease down to the cutter's reach.
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/raster.hpp"

namespace cncstream::cam {

struct PencilOptions {
  double step = 0.1;              // mm: the CL grid the creases are found on
  double min_turn_deg = 20;       // the CL's slope turns by at least this across a crease node
  double min_length = 1;          // mm: shorter creases are left out
  double sample_step = 0.02;      // mm: each move is checked against the exact CL this often
  double tolerance = 0.002;       // mm: merged moves ride at most this above the CL (never below it)
  std::optional<XYLattice> lattice;  // the G-code's: points are put on it
};

// Creases inside `bounds` where `wanted(x, y)` (e.g. where an earlier,
// larger cutter left material); each a polyline of tip points on or above
// the exact CL (a move that would dip between its ends gets the point where
// it dips, raised onto the CL), then merged where a straight move stays on
// or above the CL and within the tolerance of it. Chains follow
// neighbouring crease nodes.
std::vector<Polyline> pencil_passes(const ClEngine& engine, const XYBounds& bounds, const PencilOptions& options,
                                    const std::function<bool(double, double)>& wanted);

}  // namespace cncstream::cam
