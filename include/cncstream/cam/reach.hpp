#pragma once
// The reach limit of a cutter: the surface it leaves when its tip visits every
// node of a dense CL grid, as if passes ran at every node in both directions.
// Material above it cannot be removed by this cutter at any stepover (a pocket
// narrower than the cutter, an inside corner); material between it and the
// raster's machined surface is scallop. Splitting the residual this way keeps
// a 2.5 mm deep gap between letters out of the scallop statistics.
#include <cstdint>
#include <vector>

#include "cncstream/cam/checkpoint.hpp"
#include "cncstream/cam/cl_grid.hpp"
#include "cncstream/cam/cutter.hpp"

namespace cncstream::cam {

// A dense CL lattice for reach_heights(): pitch about pitch_x and pitch_y,
// placed so that every node of `at` lies on it or on a fixed fraction of a
// cell (few distinct offsets keep the stamp tables few), covering x0..x1,
// y0..y1.
GridSpec reach_lattice(const GridSpec& at, double x0, double y0, double x1, double y1, double pitch_x, double pitch_y);

// Per node of `at` with wanted[k] != 0: the lowest height any placement of the
// cutter's tip on a node of `cl` leaves there (min over CL nodes within R of
// CL + profile(distance)); +inf where no CL node is within R; NaN where not
// wanted. Runs in the caller's oneTBB task arena (a job limits it with
// run_with_thread_limit). `checkpoint` is called as bands of rows are done
// (see checkpoint.hpp). Throws std::invalid_argument on a mask of the wrong size.
std::vector<double> reach_heights(const ClGrid& cl, const Cutter& cutter, const GridSpec& at,
                                  const std::vector<std::uint8_t>& wanted, const Checkpoint& checkpoint = {});

}  // namespace cncstream::cam
