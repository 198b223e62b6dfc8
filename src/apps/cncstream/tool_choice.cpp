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

std::optional<jobs::FeedsRequest> resolve_tool_options(ToolpathOptions& o) {
  ToolLookup lookup(o.tool_library);
  auto operation_tool = [&](std::string& text, std::optional<int>& number) -> std::optional<jobs::OperationTool> {
    if (text.empty()) return std::nullopt;
    const tooling::ToolChoice c = lookup.choose(text);
    text = c.spec();  // the jobs take specs, and the library's number for the program's T word
    number = c.tool ? std::optional<int>(c.tool->number) : std::nullopt;
    return jobs::OperationTool{c.geometry, c.tool ? std::optional<tooling::Tool>(*c.tool) : std::nullopt};
  };
  const auto finish = operation_tool(o.tool, o.tool_number);
  const auto rough = operation_tool(o.rough, o.rough_tool_number);
  const auto rest = operation_tool(o.rest, o.rest_tool_number);
  if (o.material.empty() || !finish) return std::nullopt;
  jobs::FeedsRequest q;
  q.material = o.material;
  q.finish = *finish;
  q.rough = rough;
  q.rest = rest;
  q.spec_flutes = o.flutes > 0 ? o.flutes : 2;
  // The operator's limits; the machine's fill in the rest (apply_feeds).
  q.limits.spindle_max = o.spindle_max;
  q.limits.spindle_min = o.spindle_min;
  q.limits.max_feed_xy = o.max_feed;
  q.limits.max_feed_z = o.max_feed_z;
  if (o.feed_given) q.feed = o.feed;
  if (o.plunge_feed_given) q.plunge_feed = o.plunge_feed;
  if (o.rpm_given) q.rpm = o.rpm;
  q.rough_feed = o.rough_feed;
  // The table knows the material, or the command stops before any work.
  tooling::builtin_materials().find(o.material);
  return q;
}

jobs::FeedsPlan apply_feeds(jobs::ToolpathParams& p, std::optional<jobs::FeedsRequest> request,
                            const tooling::MachineLimits& machine) {
  if (!request) return {};
  auto& l = request->limits;
  auto fill = [](double& given, double machine_value) {
    if (!(given > 0)) given = machine_value;
  };
  fill(l.spindle_max, machine.spindle_max > 0 ? machine.spindle_max : kDefaultSpindleMax);
  fill(l.spindle_min, machine.spindle_min);
  fill(l.max_feed_xy, machine.max_feed_xy);
  fill(l.max_feed_z, machine.max_feed_z);
  return jobs::apply_material_feeds(p, *request);
}

}  // namespace cncstream::app
