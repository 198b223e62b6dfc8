#pragma once
// A job's operation parameters as the API takes them (the options of
// `cncstream toolpath`), checked field by field: a wrong type or an absurd
// value is an ApiError 400 naming the field, before anything is allocated.
#include <nlohmann/json.hpp>

#include "cncstream/daemon/config.hpp"
#include "cncstream/daemon/file_store.hpp"
#include "cncstream/jobs/toolpath_job.hpp"

namespace cncstream::daemon {

struct CheckedParams {
  jobs::ToolpathParams params;  // part.stl and part.mesh left for the caller
  nlohmann::json canonical;     // every field with its value: the cache key's half
  double grid_nodes = 0;        // samples the tool path will take (estimate)
};

// `file` gives the part's box for the grid estimate.
CheckedParams check_toolpath_params(const nlohmann::json& j, const FileInfo& file, const Limits& limits);

}  // namespace cncstream::daemon
