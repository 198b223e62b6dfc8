#include "tool_choice.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "toolpath_options.hpp"

namespace cncstream::app {

ToolLookup::ToolLookup(std::filesystem::path path)
    : path_(path.empty() ? tooling::default_tool_library_path() : std::move(path)) {}

tooling::ToolChoice ToolLookup::choose(const std::string& text) {
  // A spec needs no library: a broken or missing file does not stop it.
  if (const auto colon = text.find(':');
      colon != std::string::npos && tooling::shape_from_name(std::string_view(text).substr(0, colon)))
    return tooling::choose_tool({}, text);
  if (!library_) library_ = tooling::load_tool_library(path_);
  try {
    return tooling::choose_tool(*library_, text);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(fmt::format("{} (tool library {})", e.what(), path_.string()));
  }
}

std::optional<jobs::FeedsRequest> resolve_tool_options(ToolpathOptions& o, const tooling::MachineLimits& machine) {
  ToolLookup lookup(o.tool_library);
  auto operation_tool = [&](std::string& text) -> std::optional<jobs::OperationTool> {
    if (text.empty()) return std::nullopt;
    const tooling::ToolChoice c = lookup.choose(text);
    text = c.spec();  // the jobs take specs
    return jobs::OperationTool{c.geometry, c.tool ? std::optional<tooling::Tool>(*c.tool) : std::nullopt};
  };
  const auto finish = operation_tool(o.tool);
  const auto rough = operation_tool(o.rough);
  const auto rest = operation_tool(o.rest);
  if (o.material.empty() || !finish) return std::nullopt;
  jobs::FeedsRequest q;
  q.material = o.material;
  q.finish = *finish;
  q.rough = rough;
  q.rest = rest;
  q.spec_flutes = o.flutes > 0 ? o.flutes : 2;
  q.limits = machine;
  if (o.spindle_max > 0) q.limits.spindle_max = o.spindle_max;
  if (o.spindle_min > 0) q.limits.spindle_min = o.spindle_min;
  if (o.max_feed > 0) q.limits.max_feed_xy = o.max_feed;
  if (o.max_feed_z > 0) q.limits.max_feed_z = o.max_feed_z;
  if (o.feed_given) q.feed = o.feed;
  if (o.plunge_feed_given) q.plunge_feed = o.plunge_feed;
  if (o.rpm_given) q.rpm = o.rpm;
  q.rough_feed = o.rough_feed;
  // The table knows the material, or the command stops before any work.
  tooling::builtin_materials().find(o.material);
  return q;
}

jobs::FeedsPlan apply_feeds(jobs::ToolpathParams& p, const std::optional<jobs::FeedsRequest>& request) {
  if (!request) return {};
  return jobs::apply_material_feeds(p, *request);
}

}  // namespace cncstream::app
