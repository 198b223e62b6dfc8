// A job's `params` as a client sends them (JSON) -> check_toolpath_params
// against a few parts: every wrong type or absurd value is a 400 naming the
// field, and what passes is a tool path the engine can sample (the grid
// within the limit, the canonical form the cache key is made of).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "cncstream/daemon/job_params.hpp"
#include "cncstream/daemon/json_body.hpp"

using namespace cncstream::daemon;
using nlohmann::json;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  json params;
  try {
    params = parse_json(std::string_view(reinterpret_cast<const char*>(data), size), "");
  } catch (const ApiError&) {
    return 0;
  }
  static const Limits limits;
  FileInfo parts[3];
  parts[0].bbox = {0, 0, 0, 120, 100, 10};         // a plaque
  parts[1].bbox = {-2e3, -2e3, -50, 2e3, 2e3, 50};  // as large as a part may be
  parts[2].bbox = {0, 0, 0, 0, 0, 0};               // a degenerate one
  for (auto& part : parts) {
    part.kind = "stl";
    try {
      const CheckedParams c = check_toolpath_params(params, part, limits);
      if (!(c.grid_nodes >= 1 && c.grid_nodes <= limits.max_grid_nodes)) std::abort();
      if (!(c.params.cutter.diameter() > 0 && c.params.stepover > 0 && c.params.feed > 0)) std::abort();
      (void)c.canonical.dump();  // the cache key: dumped strictly by the job manager
    } catch (const ApiError& e) {
      if (e.status != 400 || e.message.rfind("params", 0) != 0) std::abort();
    }
  }
  return 0;
}
