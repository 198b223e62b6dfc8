#pragma once
// Waterline finishing of the steep parts of a surface: at each level the
// contour of the CL surface (where the tip, at that height, touches the part),
// kept where the surface is at least `steep_angle` steep. Contours come from
// the CL grid by marching squares refined with exact point queries; between
// two contour points the CL is queried again along the chord and the path is
// raised wherever it would dip into it, so a waterline never gouges (it
// stays level within the chord's sag, a few microns).
//
// Each contour keeps the region the tip may go down to on its left: the part
// is on the cutter's right, climb milling for a clockwise spindle (M3).
// Levels run from the top down; pieces of one level are taken nearest first;
// a piece close to the last one is joined to it by a bridge (up, across,
// down) above every CL point under it, otherwise it is a separate piece (the
// program retracts between pieces).
#include <cstddef>
#include <optional>
#include <vector>

#include "cncstream/cam/checkpoint.hpp"
#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/raster.hpp"
#include "cncstream/cam/slope_map.hpp"

namespace cncstream::cam {

struct WaterlineOptions {
  double z_step = 0.5;            // between levels, mm
  // Levels spaced by the walls they cut (when > 0, instead of z_step): two
  // levels' passes touch a wall of slope a at wall_spacing / sin(a) apart
  // along it, so each band between levels is at most wall_spacing times the
  // sine of the gentlest node in it that is at least wall_angle_deg steep
  // (gentler ground is the rows'): never closer than wall_spacing *
  // sin(wall_angle_deg), up to wall_spacing apart on vertical walls.
  double wall_spacing = 0;
  double wall_angle_deg = 35;
  double steep_angle_deg = 45;    // contours where the surface is at least this steep
  double tolerance = 0.002;       // mm: contour points within this of the exact contour
  // mm: points are merged where the straight move stays within this of
  // them on the free side (0: every contour point is kept, for arcs).
  double simplify_tolerance = 0;
  double sample_step = 0.05;      // mm: the CL is queried this often along every chord
  double bridge_max = 0;          // mm: join pieces closer than this by a bridge; 0: 4 cutter radii
  // The G-code's decimal grid: every point is put on it (on the free side,
  // where the CL lets it be at the level), so printing moves none of them
  // (beside a CL cliff a rounded half micron is a deep vertical error); the
  // levels lie on its Z values (lattice.z0 + k * step).
  std::optional<XYLattice> lattice;
  // A level just above each flat area of the CL (a terrace at least
  // flat_min_area large, the cutter's disc area / 4 by default): the
  // waterline there runs at the foot of the walls rising from it, into the
  // corner the rows beside a wall and the levels a step apart cannot reach.
  bool flat_levels = true;
  double flat_min_area = 0;
  double top = HUGE_VAL;          // highest level (tip height); default: the grid's highest CL
  double bottom = -HUGE_VAL;      // lowest level; default: the grid's lowest CL
};

struct WaterlinePath {
  std::vector<Polyline> pieces;  // in cutting order; the program retracts between them
  std::vector<double> levels;    // the levels used, top down
  double step_min = 0, step_max = 0;  // between the spaced levels (the flat areas' levels aside)
  std::size_t contours = 0;      // contours traced (before the steepness split)
  std::size_t point_queries = 0;
};

// `grid`: a CL grid of `engine` (any uniform spacing: it places the
// contours; the engine makes them exact); `slope`: the slope map of the same
// grid. Throws std::invalid_argument for a non-positive step or tolerance.
WaterlinePath build_waterline(const ClEngine& engine, const ClGrid& grid, const SlopeMap& slope,
                              const WaterlineOptions& options, const Checkpoint& checkpoint = {});

}  // namespace cncstream::cam
