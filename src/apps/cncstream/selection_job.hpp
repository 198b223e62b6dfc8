#pragma once
// Cutter-type selection as the CLI runs it (`cncstream select` and `plan`):
// the part, both cutters' exact CL grids and the per-node choice, both
// cutters' raster finishing paths machined by the shared cut simulation, the
// scallops, and the combined plan.
#include <CLI/CLI.hpp>

#include <filesystem>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "cncstream/cam/cutter_selection.hpp"
#include "cncstream/cam/deviation.hpp"
#include "cncstream/cam/raster.hpp"
#include "cncstream/cam/scallop.hpp"
#include "cncstream/gcode/motion_planner.hpp"

namespace cncstream::app {

struct SelectionOptions {
  PartOptions part;
  std::string tools = "ball:3.175,bull:3.175:0.79";
  double stepover = 0.4;
  double step = 0.05;      // along the passes
  std::string direction = "x";
  double scallop_tol = 0.01;
  double reach_pitch = -1; // reach-limit lattice, mm; 0: no scallop/unreachable split; < 0: min(0.15, stepover/3)
  double sim_along = 0;    // cut simulation column spacing along the passes; 0: one per stepover
  double feed = 1000, plunge_feed = 300, rpm = 18000;
  double max_rate = 500, accel = 10;  // for predicted times ($110-$112, $120-$122)
  unsigned threads = 0;
  bool nodes_csv = false;  // also write every CL point's heights, d and choices (large)
};

void add_selection_options(CLI::App* sub, SelectionOptions& o);

struct CutterRun {
  Cutter cutter;
  RasterPath path;
  std::vector<double> machined;  // on the simulation grid
  ScallopMap scallops;           // scallop and unreachable material, split by the reach limit
  std::vector<double> reach;     // the cutter's reach limit per simulation node (NaN where not computed)
  ScallopStats estimate_2d;      // the thesis's 2-D tangent estimate over the part
};

struct SelectionResult {
  SelectionOptions options;
  std::size_t facets = 0;
  CutterPair pair;
  Vec3 work_offset;                  // model -> work coordinates (G-code)
  RemovalChoice choice;              // on the analysis grid
  SlopeProfile profile;
  DesignHeights design;              // on the simulation grid
  CutterRun ball, radiused;
  std::vector<std::int8_t> min_scallop_choice;  // per simulation node: Choice, or 2 = equal
  double seconds = 0;
  std::vector<std::pair<std::string, double>> timings;
  std::string table() const;  // Table 4.1 and the choice summary, for a person
};

SelectionResult run_selection(const SelectionOptions& o);

// JSON, CSV and PNGs into `dir` (created). Returns the files written.
std::vector<std::filesystem::path> write_selection_report(const SelectionResult& r, const std::filesystem::path& dir);

}  // namespace cncstream::app
