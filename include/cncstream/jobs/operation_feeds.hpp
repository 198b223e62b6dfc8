#pragma once
// Feeds and speeds per operation of a tool path job (tooling/feeds_speeds.hpp
// applied to its roughing, finishing and rest machining): what the CLI's
// --material and the daemon's "material" both use. The operator's values
// win; the rest are computed and set on the job's parameters.
#include <optional>
#include <string>
#include <vector>

#include "cncstream/jobs/toolpath_job.hpp"
#include "cncstream/tooling/feeds_speeds.hpp"
#include "cncstream/tooling/tool_library.hpp"

namespace cncstream::jobs {

struct OperationTool {
  tooling::ToolGeometry geometry;
  std::optional<tooling::Tool> tool;  // from the library: its flutes and cutting data
  std::string label() const;          // "T3 1/8 tapered ball [taper:1:5:3.175]" or "[ball:3.175]"
};

struct FeedsRequest {
  std::string material;  // a name or alias of the material table
  OperationTool finish;
  std::optional<OperationTool> rough, rest;
  int spec_flutes = 2;  // a tool given as a spec
  tooling::MachineLimits limits;
  // Given by the operator (they win over the material).
  std::optional<double> feed, plunge_feed, rpm, rough_feed;
};

struct OperationFeeds {
  std::string operation;  // "roughing", "finishing", "rest machining"
  std::string tool;       // OperationTool::label()
  int flutes = 2;
  double depth_of_cut = 0, radial_engagement = 0;
  tooling::Feeds feeds;
};

struct FeedsPlan {
  std::string material;  // "hardwood (walnut)"
  std::vector<OperationFeeds> operations;
};

// Computes each operation's feeds from the job's engagement (finishing: the
// stock the roughing leaves, at the stepover; roughing: the step-down at its
// stepover; rest machining: half its diameter) and sets p.feed, p.rpm,
// p.plunge_feed, p.rough_feed, p.rough_rpm, p.rest_feed and p.rest_rpm where
// the operator did not give them (rounded to whole mm/min and rpm). Throws
// std::invalid_argument for an unknown material, listing the table's.
FeedsPlan apply_material_feeds(ToolpathParams& p, const FeedsRequest& request);

// "  feeds and speeds for hardwood (walnut):" and per operation: tool, rpm and
// what set it, feed and what set it, the chip that results and the removal
// rate; then any warning. Empty for an empty plan.
std::string feeds_plan_text(const FeedsPlan& plan);
// Only the operations the program has (a roughing found unneeded is left out).
std::string feeds_plan_text(const FeedsPlan& plan, const ToolpathProgram& program);

}  // namespace cncstream::jobs
