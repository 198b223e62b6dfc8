#pragma once
// A job's operation parameters as the API takes them (the options of
// `cncstream toolpath`), checked field by field: a wrong type or an absurd
// value is an ApiError 400 naming the field, before anything is allocated.
#include <nlohmann/json.hpp>

#include "cncstream/daemon/config.hpp"
#include "cncstream/daemon/file_store.hpp"
#include "cncstream/jobs/toolpath_job.hpp"
#include "cncstream/tooling/feeds_speeds.hpp"
#include "cncstream/tooling/tool_library.hpp"

namespace cncstream::daemon {

struct CheckedParams {
  jobs::ToolpathParams params;  // part.stl and part.mesh left for the caller
  nlohmann::json canonical;     // every field with its value: the cache key's half
  double grid_nodes = 0;        // samples the tool path will take (estimate)
};

// `file` gives the part's box for the grid estimate. "tool", "rough" and
// "rest" may name a tool of `tools` (number or name; the canonical params
// hold its spec); with "material", the feeds and rpm not given are computed
// per operation within `machine` (jobs/operation_feeds.hpp) and the
// canonical params hold them.
CheckedParams check_toolpath_params(const nlohmann::json& j, const FileInfo& file, const Limits& limits,
                                    const tooling::ToolLibrary* tools = nullptr,
                                    const tooling::MachineLimits& machine = {});

}  // namespace cncstream::daemon
