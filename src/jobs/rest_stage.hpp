#pragma once
// Rest machining with a smaller cutter (`--rest SPEC`): where the finishing
// cutter cannot reach the part (its reach limit, the surface it leaves with
// its tip on every node of a dense CL lattice, stands above the part by more
// than the tolerance: grooves, gaps and inside corners narrower than it),
// the smaller cutter's rows clipped to those places and the cutter's radius
// around them, then pencil passes along the creases there. Private to the
// jobs layer.
#include <cstddef>
#include <vector>

#include "cncstream/cam/checkpoint.hpp"
#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/raster.hpp"
#include "cncstream/cam/zlevel_roughing.hpp"
#include "cncstream/jobs/toolpath_job.hpp"

namespace cncstream::jobs {

struct RestStage {
  cam::Cutter cutter;
  std::vector<cam::Polyline> pieces;  // model coordinates, in cutting order; empty: nothing left to it
  double stepover = 0;           // of its rows
  std::size_t pencils = 0;       // the last pieces: pencil passes along the creases there (pencil.hpp)
  std::size_t nodes = 0;         // analysis nodes where the finishing cutter leaves more than `threshold`
  double threshold = 0;          // mm
  double most_left = 0;          // the most the finishing cutter leaves there, mm
  geometry::Vec3 most_left_at;             // model coordinates
  // Where the finishing cutter leaves more than the smaller one may take in
  // one pass (a gap narrower than it, as deep as the part): Z-levels of the
  // smaller cutter there first, in rounds on finer grids (as the rest
  // roughing before the finishing); none where it may.
  std::vector<cam::RoughingPath> levels;
  double level_leave = 0;
  // The deepest any of its moves cuts, measured against the stock the
  // finishing cutter leaves (its reach limit, its cusps on top).
  double depth = 0;
};

// `finish_engine`: the finishing cutter's CL engine over `mesh`; `region`
// and `lattice`: the finishing rows'. Throws std::invalid_argument for a
// rest cutter not smaller than the finishing cutter, or one that would cut
// deeper than its maximum depth in one pass.
RestStage plan_rest(const ToolpathParams& p, const geometry::Mesh& mesh, const cam::ClEngine& finish_engine, const cam::XYBounds& region,
                    const cam::XYLattice& lattice, const cam::Checkpoint& checkpoint);

}  // namespace cncstream::jobs
