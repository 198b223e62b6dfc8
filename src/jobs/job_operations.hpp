#pragma once
// The operations of a tool path job with a stock (toolpath_job.hpp): whether
// the finishing pass alone would cut deeper than its cutter may, the Z-level
// roughing that comes first when it would, the rest roughing with the
// finishing cutter where the roughing cutter could not reach deep enough,
// and the program of them all with the tool change between the cutters.
// Private to the jobs layer.
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cncstream/cam/checkpoint.hpp"
#include "cncstream/cam/stock.hpp"
#include "cncstream/cam/zlevel_roughing.hpp"
#include "cncstream/jobs/toolpath_job.hpp"
#include "rest_stage.hpp"

namespace cncstream::jobs {

struct RoughingStage {
  WorkStock stock;                   // work coordinates
  double finish_max_depth = 0;       // the finishing cutter's
  double finish_depth_alone = 0;     // the deepest the finishing pass would cut from the stock alone
  // ... after the roughing (and the rest roughing), measured against the
  // stock they leave (pass_depth.hpp); = alone without one.
  double finish_depth = 0;
  std::optional<RoughingPath> path;  // model coordinates; none when the finishing pass is within its depth
  double rough_max_depth = 0;
  // With the finishing cutter, where the roughing cutter could not reach and
  // the finishing pass would still cut deeper than it may (model
  // coordinates), in order: each from the stock the ones before leave, near
  // what they left too deep, on a finer grid; none when it would not.
  std::vector<RoughingPath> rest;
  double rest_leave = 0;  // mm of stock the rest roughing leaves
  double rest_step_down = 0;
  std::size_t rest_spots = 0;  // points along the finishing's moves too deep after the roughing
  // A height-map stock in model coordinates (the roughing's surface).
  std::shared_ptr<const HeightFieldStock> surface;
  std::vector<std::string> notes;
};

// A round cutter's roughing stepover: loops close enough that the scallops
// between them stay under a quarter of the step-down (the roughing allows
// for a further grid cell, at most a sixth of the radius).
double round_stepover(const Cutter& c, double step_down);

// The stock after a roughing path cut into it.
HeightFieldStock stock_after(const HeightFieldStock& stock, const RoughingPath& path);

// Throws std::invalid_argument for a stock that does not hold the part, a
// leave or depth that leaves no room for a level, or a roughing that cannot
// keep the finishing pass within its depth.
// `finishing`: the finishing operation's pieces (model coordinates).
RoughingStage plan_roughing(const ToolpathParams& p, const Mesh& mesh, const std::vector<Polyline>& finishing,
                            const Vec3& work_offset, const Checkpoint& checkpoint);

// The finishing operation's summary from its program's stats.
OperationSummary finishing_summary(const ToolpathProgram& r, const ToolpathParams& p, const ProgramStats& stats);

// The whole program (roughing, tool change, rest roughing, finishing, tool
// change, rest machining) into r.gcode, r.stats and r.operations; the notes
// into r.notes. Either stage may be missing (null), not both.
void compose_job(ToolpathProgram& r, const ToolpathParams& p, const RoughingStage* rough, const RestStage* rest,
                 MachiningParams mp);

}  // namespace cncstream::jobs
