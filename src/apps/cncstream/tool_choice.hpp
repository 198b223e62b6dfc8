#pragma once
// The CLI's tool library and feeds and speeds: `--tool 3` or `--tool "1/8
// tapered ball"` picks from the library (a spec still works), and
// `--material walnut` computes the rpm and feeds the operator did not give,
// per operation, within the machine's limits.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "cncstream/jobs/toolpath_job.hpp"
#include "cncstream/tooling/feeds_speeds.hpp"
#include "cncstream/tooling/tool_library.hpp"

namespace cncstream::app {

struct ToolpathOptions;

// The library file, read once and only when a name or number is to be
// looked up (a spec needs no library).
class ToolLookup {
 public:
  explicit ToolLookup(std::filesystem::path path = {});
  tooling::ToolChoice choose(const std::string& text);
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  std::optional<tooling::ToolLibrary> library_;
};

// The feeds of one operation, for the plan.
struct OperationFeeds {
  std::string operation;  // "finishing", "roughing", "rest machining"
  std::string tool;       // "T3 1/8 tapered ball [taper:1:5:3.175]" or "[ball:3.175]"
  int flutes = 2;
  double depth_of_cut = 0, radial_engagement = 0;
  tooling::Feeds feeds;
};

struct FeedsPlan {
  std::string material;  // as the table names it ("hardwood" for walnut)
  std::vector<OperationFeeds> operations;
};

// Turns --tool, --rough and --rest into specs (from the library where they
// name a tool) and, with --material, sets the feeds and rpm not given on the
// command line (--feed, --rpm, --plunge-feed and --rough-feed win). Returns
// the feeds per operation (empty without a material). Throws for an unknown
// or ambiguous tool or material, listing the candidates.
FeedsPlan resolve_tool_options(ToolpathOptions& o, const tooling::MachineLimits& machine = {});

// "feeds and speeds for hardwood (walnut):" and a line per operation: tool,
// rpm and what set it, feed and what set it, the chip that results and the
// material removal rate; then any warning.
std::string feeds_plan_text(const FeedsPlan& plan);
// Only the operations the program has (a roughing the job found unneeded is left out).
std::string feeds_plan_text(const FeedsPlan& plan, const jobs::ToolpathProgram& program);

}  // namespace cncstream::app
