#pragma once
// Cutter-type selection (thesis chapter 4), the job behind `cncstream select`
// and `plan`: the part, both cutters' exact CL grids and the per-node choice,
// both cutters' raster finishing paths machined by the shared cut simulation,
// the scallops split from material no stepover removes, and Table 4.1.
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cncstream/cam/cutter_selection.hpp"
#include "cncstream/cam/deviation.hpp"
#include "cncstream/cam/raster.hpp"
#include "cncstream/cam/scallop.hpp"
#include "cncstream/jobs/job_control.hpp"
#include "cncstream/jobs/part_source.hpp"

namespace cncstream::jobs {

struct SelectionParams {
  PartSource part;
  cam::CutterPair cutters;       // the ball and the radiused cutter, same diameter
  // A third cutter on the same passes, beside the pair (its scallops and what
  // it cannot reach; the choice stays the pair's): the sign maker's tapered
  // ball against ball and bull-nose (issue 28).
  std::optional<cam::Cutter> tapered;
  double stepover = 0.4;
  double step = 0.05;       // along the passes
  cam::RasterDirection direction = cam::RasterDirection::X;
  double scallop_tol = 0.01;
  double reach_pitch = -1;  // reach-limit lattice, mm; 0: no scallop/unreachable split; < 0: min(0.15, stepover/3)
  double sim_along = 0;     // cut simulation column spacing along the passes; 0: one per stepover
};

struct CutterRun {
  cam::Cutter cutter;
  cam::RasterPath path;
  std::vector<double> machined;  // on the simulation grid
  cam::ScallopMap scallops;           // scallop and unreachable material, split by the reach limit
  std::vector<double> reach;     // the cutter's reach limit per simulation node (NaN where not computed)
  cam::ScallopStats estimate_2d;      // the thesis's 2-D tangent estimate over the part
};

struct SelectionResult {
  SelectionParams params;
  std::size_t facets = 0;
  cam::CutterPair pair;
  geometry::Vec3 work_offset;                  // model -> work coordinates (G-code)
  cam::RemovalChoice choice;              // on the analysis grid
  cam::SlopeProfile profile;
  cam::DesignHeights design;              // on the simulation grid
  CutterRun ball, radiused;
  std::optional<CutterRun> tapered;  // when params.tapered
  // The runs in the report's order: ball, radiused, then the tapered.
  std::vector<const CutterRun*> runs() const;
  std::vector<CutterRun*> runs();
  std::vector<std::int8_t> min_scallop_choice;  // per simulation node: Choice, or 2 = equal
  double seconds = 0;
  std::vector<std::pair<std::string, double>> timings;
  std::string table() const;  // Table 4.1 and the choice summary, for a person
};

// Stages: "load", "CL grids + raster paths", "choice", "design heights",
// "cut simulation", "reach limits", "scallops", "done". Throws Cancelled on a
// stop request.
SelectionResult run_selection(const SelectionParams& params, const JobControl& control = {});

}  // namespace cncstream::jobs
