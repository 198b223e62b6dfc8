#pragma once
// Z-level roughing from a stock block. The CL engine is that of the cutter
// grown by the stock to leave (grown_cutter): its tip height plus `leave` is
// the lowest the roughing cutter's tip may go at (x, y) and still keep
// `leave` of material on the part in every direction. At each level z the
// tip region {grown CL + leave <= z}, limited to the stock's XY box grown by
// the cutter radius (round at the corners; so the block's sides are
// cleared), is cleared by
// contour-parallel loops `stepover` apart (iso-lines of the region's distance
// transform), ordered inside out (or outside in), the region's own boundary
// last, in the climb direction for a clockwise spindle. The boundary comes
// from the CL grid by marching squares refined with exact point queries.
//
// Why no move cuts deeper than the step down: the regions shrink as the
// levels go down, and every level clears its whole region (loops closer than
// the cutter radius, the boundary followed), so wherever the tip goes at a
// level, the cutter's footprint was cleared to the level above (a round
// cutter to its scallop above it: its levels are closer by that much). Entries ramp
// along a loop of the region from the level above (over the length the ramp
// angle needs, then a whole lap at the level); links between loops stay
// down when the straight move lies inside the region, otherwise the tool
// lifts to just above the level above (when the move over lies over its
// region) or to the clearance height above the stock.
//
// The regions come from a grid (cells of min(R / 6, sqrt(2 * tolerance *
// R)), so a chord leaves a region by at most tolerance / 2): a part of a
// region narrower than a cell (the far end of a narrow bay) can be missed,
// and is then left uncut, never gouged.
#include <cstddef>
#include <optional>
#include <vector>

#include "cncstream/cam/checkpoint.hpp"
#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/cutter.hpp"
#include "cncstream/cam/raster.hpp"

namespace cncstream::cam {

class HeightFieldStock;

// A rectangular block of material in model coordinates, top at `top`. With
// a surface (an earlier operation's result; it must outlive the call), the
// stock's top is that surface where it lies lower than `top` (beyond the
// surface's grid: `top`): levels start below its highest point and each
// level clears only within reach of material more than tolerance / 5 above
// it (a level cut before stands up to the G-code's rounding of Z above it).
struct StockBlock {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  double top = 0;
  const HeightFieldStock* surface = nullptr;
};

enum class ClearingOrder { InsideOut, OutsideIn };

struct RoughingParams {
  double step_down = 3;      // mm between levels at most (the depth of cut of any move)
  double stepover = 0;       // mm between loops; 0: 40 % of the diameter (capped so loops overlap)
  double leave = 0.3;        // mm of stock to leave; the engine's cutter must be grown by it
  double tolerance = 0.05;   // mm: the region's boundary within this of exact (sets the grid)
  bool climb = true;         // climb milling for a clockwise spindle (M3)
  ClearingOrder order = ClearingOrder::InsideOut;
  double ramp_angle_deg = 3; // entries descend at most this steeply (into a loop shorter than R: plunged)
  double min_ramp_loop = 0;  // mm: shortest loop to ramp along; 0: pi * R / 2
  double clearance = 2;      // mm above the stock top (and above a cleared level) for moves over
  bool flat_levels = true;   // extra levels at the part's flat areas
  double flat_min_area = 0;  // mm^2 of flat CL for an extra level; 0: the cutter's disc area / 4
  double grid_step = 0;      // mm; 0: from the radius and tolerance (see zlevel_roughing.cpp)
  std::optional<double> bottom;  // no level below this tip height
  // Rest roughing: not empty, the roughing clears only where its tip is
  // within near_radius (XY) of one of these points (where an earlier
  // measurement found too much material; the window is up to a cell and a
  // cell's diagonal wider, from the grid), and computes only the part of
  // its grid that reaches them. The window is the same at every level, so what
  // a level clears was cleared to the level above as before, and no move
  // cuts deeper than the step down. z: the height the stock there must come
  // within step_down + leave of (a finishing tip): where the cutter's tip
  // can go low enough there, a level is added if none lies between that
  // and z + step_down + leave less the scallop between loops.
  std::vector<geometry::Vec3> near;
  double near_radius = 0;
};

// One cut: lift first (if lift_before: straight up to lift_z, across at
// lift_z, straight down to points[0]), then the points in order at the feed,
// the first `entry_points` after points[0] at the plunge feed (the ramp).
// Without lift_before, the pass follows the previous one by a straight feed
// move at the level (a link inside the region).
struct RoughingPass {
  Polyline points;
  bool lift_before = false;
  double lift_z = 0;
  std::size_t entry_points = 0;
};

struct RoughingLevel {
  double z = 0;       // tip height
  bool flat = false;  // an extra level at a flat area of the part
  std::vector<RoughingPass> passes;
};

struct RoughingStats {
  std::size_t loops = 0;
  std::size_t passes = 0;
  std::size_t high_lifts = 0;  // to the clearance height
  std::size_t low_lifts = 0;   // to just above the level above
  std::size_t short_entries = 0;  // ramps along a loop shorter than min_ramp_loop
  std::size_t point_queries = 0;
  std::size_t corners_dropped = 0;  // sharp corners outside the level above's boundary
  double cut_length = 0;       // mm at feed (ramps and links included)
};

struct RoughingPath {
  std::vector<RoughingLevel> levels;  // top down
  Cutter cutter;                       // the roughing cutter
  double leave = 0;
  double stepover = 0;                 // used
  double clearance_z = 0;              // highest stock top + clearance
  // Material left above the part grown by `leave`, measured vertically, is
  // at most this where the cutter reaches (plus the tolerance): the largest
  // gap between levels plus the scallop between loops on a round cutter
  // (at most step_down: a round cutter's levels are closer by the scallop).
  double terrace_bound = 0;
  GridSpec grid;                       // of the region computation
  RoughingStats stats;
};

// `grown`: the CL engine of grown_cutter(cutter, params.leave). Throws
// std::invalid_argument for bad parameters, a stock without area, or an
// engine whose cutter is not the grown cutter. `checkpoint` gets the
// fraction of levels done.
RoughingPath build_zlevel_roughing(const ClEngine& grown, const Cutter& cutter, const StockBlock& stock,
                                   const RoughingParams& params, const Checkpoint& checkpoint = {});

// The path as the tool moves it, in one polyline for a stock model
// (path_machining.hpp's machine_path joins its points by straight moves):
// down from the clearance height to the first pass, each pass's lift as
// points of its own (straight up, across, straight down), the links of
// passes without one straight at the level, and up to the clearance height
// at the end. Model coordinates, as the passes are; the G-code rounds Z up
// to its resolution (cutting less) and fits arcs within its tolerance.
Polyline roughing_moves(const RoughingPath& path);

// The levels (top down) below a stock top: every step_down from the top, the
// lowest of `tips` (tip heights: the grown CL plus leave), and (if on) the
// heights of flat areas: where at least min_flat_area of `flat_tips` (tip
// heights of nodes whose CL is locally level, one per node of `cell_area`
// mm^2) lie within tolerance / 5 of each other. Pure; exposed for tests.
// `flat` marks the extra levels.
struct LevelPlan {
  std::vector<double> z;
  std::vector<bool> flat;
};
LevelPlan plan_levels(const std::vector<double>& tips, const std::vector<double>& flat_tips, double cell_area,
                      double stock_top, const RoughingParams& params, double min_flat_area);

}  // namespace cncstream::cam
