#pragma once
// The roughing of a tool path job with a stock (toolpath_job.hpp): the
// Z-level roughing from the stock, and whether the finishing pass needs it
// (alone it would cut deeper than its cutter may), with the rest roughing
// with the finishing cutter where the roughing cutter could not reach deep
// enough. The roughing path needs nothing of the finishing, so when it is
// asked for it is made beside the finishing; the check comes after.
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

namespace cncstream::jobs {

struct RoughingStage {
  WorkStock stock;                   // work coordinates
  double finish_max_depth = 0;       // the finishing cutter's
  double finish_depth_alone = 0;     // the deepest the finishing pass would cut from the stock alone
  // ... after the roughing (and the rest roughing), measured against the
  // stock they leave (pass_depth.hpp); = alone without one.
  double finish_depth = 0;
  cam::Cutter rough_cutter;               // the roughing's: p.rough, else the finishing cutter
  std::optional<cam::RoughingPath> path;  // model coordinates; none when the finishing pass is within its depth
  std::string path_note;             // the path's summary
  // The stock the path leaves (model coordinates), on a grid fine enough
  // for the finishing cutter: made with the path, beside the finishing.
  std::shared_ptr<const cam::HeightFieldStock> roughed;
  double rough_max_depth = 0;
  // With the finishing cutter, where the roughing cutter could not reach and
  // the finishing pass would still cut deeper than it may (model
  // coordinates), in order: each from the stock the ones before leave, near
  // what they left too deep, on a finer grid; none when it would not.
  std::vector<cam::RoughingPath> rest;
  double rest_leave = 0;  // mm of stock the rest roughing leaves
  double rest_step_down = 0;
  std::size_t rest_spots = 0;  // points along the finishing's moves too deep after the roughing
  // A height-map stock in model coordinates (the roughing's surface).
  std::shared_ptr<const cam::HeightFieldStock> surface;
  std::vector<std::string> notes;
};

// A round cutter's roughing stepover: loops close enough that the scallops
// between them stay under a quarter of the step-down (the roughing allows
// for a further grid cell, at most a sixth of the radius).
double round_stepover(const cam::Cutter& c, double step_down);

// The stock after a roughing path cut into it.
cam::HeightFieldStock stock_after(const cam::HeightFieldStock& stock, const cam::RoughingPath& path);

// The job's stock (work coordinates) and, with_path, the Z-level roughing
// from it with the roughing cutter. Throws std::invalid_argument for a stock
// that does not hold the part, or a leave or depth that leaves no room for a
// level.
RoughingStage roughing_from_stock(const ToolpathParams& p, const geometry::Mesh& mesh, const geometry::Vec3& work_offset,
                                  bool with_path, const cam::Checkpoint& checkpoint);

// With the finishing operation's pieces (model coordinates): whether a
// roughing is needed (none without p.rough when the finishing pass stays
// within its depth: s.path is then empty), the roughing path if it is and
// none was made, and the rest roughing where the finishing pass would still
// cut too deep after it; the notes say what was decided. Throws
// std::invalid_argument as roughing_from_stock does, or for a roughing that
// cannot keep the finishing pass within its depth.
void check_roughing(RoughingStage& s, const ToolpathParams& p, const geometry::Mesh& mesh,
                    const std::vector<cam::Polyline>& finishing, const geometry::Vec3& work_offset, const cam::Checkpoint& checkpoint);

}  // namespace cncstream::jobs
