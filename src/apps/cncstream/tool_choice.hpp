#pragma once
// The CLI's tool library and feeds and speeds: `--tool 3` or `--tool "1/8
// tapered ball"` picks from the library (a spec still works), and
// `--material walnut` computes the rpm and feeds the operator did not give,
// per operation, within the machine's limits (jobs/operation_feeds.hpp).
#include <filesystem>
#include <optional>
#include <string>

#include "cncstream/jobs/operation_feeds.hpp"
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

// Turns --tool, --rough and --rest into specs (from the library where they
// name a tool; its number into o.tool_number ... for the program's T words).
// With --material, returns what jobs::apply_material_feeds needs: the tools,
// the operator's values and limits (--spindle-max, --spindle-min,
// --max-feed, --max-feed-z). Throws for an unknown or ambiguous tool,
// listing the candidates.
std::optional<jobs::FeedsRequest> resolve_tool_options(ToolpathOptions& o);

// A spindle's top speed where neither the operator nor the machine says.
inline constexpr double kDefaultSpindleMax = 24000;

// The job's parameters with the material's feeds applied (none without one),
// within the operator's limits and, where the operator gave none, the
// machine's (a controller's $$: tooling::machine_limits_from_settings).
jobs::FeedsPlan apply_feeds(jobs::ToolpathParams& p, std::optional<jobs::FeedsRequest> request,
                            const tooling::MachineLimits& machine = {});

}  // namespace cncstream::app
