#pragma once
// Cutter-type selection (thesis chapter 4): at each CL point, does the ball or
// the radiused (bull-nose) cutter of the same radius remove more material?
// d = (ball centre z) - (corner-circle centre z of the radiused cutter) at
// the same XY, both from exact CL grids; the radiused cutter removes more
// where d > d_base. The thesis prints d_base wrongly (eq. 4.5 is an area, eq.
// 4.9 flips a sign); the corrected forms are in ../shared/notes/thesis-notes.md:
//   volume: d_base = [2/3 pi R^3 - pi rc^2 rk - 2/3 pi rk^3 - pi^2/2 rc rk^2] / (pi R^2)
//   area:   d_base = [pi/4 R^2 - rc rk - pi/4 rk^2] / R
// with R = rc + rk (rc core radius, rk corner radius).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "cncstream/cam/cl_grid.hpp"
#include "cncstream/cam/cutter.hpp"

namespace cncstream::cam {

enum class RemovalCriterion { Volume, Area };

// d_base for a radiused cutter (rc = core, rk = corner radius) against the
// ball of radius rc + rk. Throws std::invalid_argument unless rc > 0, rk > 0.
double d_base(RemovalCriterion criterion, double rc, double rk);

// d on a plane inclined at alpha (radians): rc (1 - sin alpha) / cos alpha.
double inclined_plane_d(double rc, double alpha);

// The slope (radians) at which inclined_plane_d falls to dbase: the radiused
// cutter removes more below it, the ball above it.
double switch_angle(double rc, double dbase);

// The pair being compared; throws std::invalid_argument unless `ball` is a
// ball and `radiused` a bull-nose of the same radius.
struct CutterPair {
  Cutter ball, radiused;
  CutterPair() = default;
  CutterPair(Cutter ball, Cutter radiused);
  double rc() const { return radiused.radius - radiused.corner_radius; }
  double rk() const { return radiused.corner_radius; }
};

enum class Choice : std::int8_t { None = -1, Ball = 0, Radiused = 1 };

struct RemovalChoice {
  GridSpec grid;
  std::vector<double> d;                 // per node; NaN where either cutter stands on the floor
  std::vector<double> slope_deg;         // surface slope under the ball (from its CL surface), NaN off part
  std::vector<Choice> by_volume, by_area;
  double d_base_volume = 0, d_base_area = 0;
  std::size_t on_part = 0;
  std::size_t radiused_by_volume = 0, radiused_by_area = 0;  // node counts
};

// The two CL grids must share one GridSpec (throws std::invalid_argument).
RemovalChoice choose_by_removal(const CutterPair& cutters, const ClGrid& ball, const ClGrid& radiused);

// Where the choice switches on the part: per slope bin (width bin_deg) the
// share of on-part nodes where the radiused cutter wins, and the slope where
// that share falls through one half, interpolated between bin centres (NaN if
// the ball never wins the majority).
struct SlopeBin {
  double lo_deg = 0, hi_deg = 0;
  std::size_t nodes = 0, radiused_by_volume = 0, radiused_by_area = 0;
};
struct SlopeProfile {
  std::vector<SlopeBin> bins;
  double switch_deg_volume = 0, switch_deg_area = 0;  // measured on the part
};
SlopeProfile slope_profile(const RemovalChoice& choice, double bin_deg = 5);

// The thesis's 2-D tangent estimate of the scallop between two passes
// `stepover` apart on a surface inclined at `slope` (radians) across the
// passes: the cutter's cross-section (its profile) touching the line at both
// passes; returns the largest height of the cusp above the line (vertical,
// like the cut simulation's residual).
double scallop_2d(const Cutter& cutter, double stepover, double slope);

}  // namespace cncstream::cam
