#include "tool_choice.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
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

namespace detail_tool_choice {

std::string tool_label(const tooling::ToolChoice& c) {
  if (!c.tool) return fmt::format("[{}]", c.spec());
  return fmt::format("T{} {} [{}]", c.tool->number, c.tool->name, c.spec());
}

// The deepest cut a tool takes by default (jobs::default_max_depth's rule:
// half the diameter for a ball or bull-nose, a quarter for a flat; a V-bit
// or tapered ball: a quarter of its top).
double default_depth(const tooling::ToolGeometry& g) {
  const double d = g.cutting_diameter();
  return g.shape == tooling::ToolShape::Ball || g.shape == tooling::ToolShape::Bull ? d / 2 : d / 4;
}

}  // namespace detail_tool_choice

FeedsPlan resolve_tool_options(ToolpathOptions& o, const tooling::MachineLimits& machine) {
  using namespace detail_tool_choice;
  ToolLookup lookup(o.tool_library);
  std::optional<tooling::ToolChoice> finish, rough, rest;
  if (!o.tool.empty()) finish = lookup.choose(o.tool);
  if (!o.rough.empty()) rough = lookup.choose(o.rough);
  if (!o.rest.empty()) rest = lookup.choose(o.rest);
  // The jobs take specs: names become their tools' specs.
  if (finish) o.tool = finish->spec();
  if (rough) o.rough = rough->spec();
  if (rest) o.rest = rest->spec();

  FeedsPlan plan;
  if (o.material.empty() || !finish) return plan;
  const tooling::Material& material = tooling::builtin_materials().find(o.material);
  plan.material = material.name == o.material ? material.name : fmt::format("{} ({})", material.name, o.material);
  tooling::MachineLimits limits = machine;
  if (o.spindle_max > 0) limits.spindle_max = o.spindle_max;
  if (o.spindle_min > 0) limits.spindle_min = o.spindle_min;
  if (o.max_feed > 0) limits.max_feed_xy = o.max_feed;
  if (o.max_feed_z > 0) limits.max_feed_z = o.max_feed_z;

  auto feeds = [&](const char* operation, const tooling::ToolChoice& c, double ap, double ae,
                   std::optional<double> rpm, std::optional<double> feed) {
    OperationFeeds f;
    f.operation = operation;
    f.tool = tool_label(c);
    f.flutes = c.tool ? c.tool->flutes : (o.flutes > 0 ? o.flutes : 2);
    f.depth_of_cut = ap;
    f.radial_engagement = ae;
    tooling::CutRequest q;
    q.geometry = c.geometry;
    q.flutes = f.flutes;
    q.material = &material;
    if (c.tool) q.tool_data = c.tool->cutting_for(o.material) ? c.tool->cutting_for(o.material)
                                                              : c.tool->cutting_for(material.name);
    q.depth_of_cut = ap;
    q.radial_engagement = ae;
    q.rpm = rpm;
    q.feed = feed;
    q.limits = limits;
    f.feeds = tooling::compute_feeds(q);
    plan.operations.push_back(f);
    return f.feeds;
  };
  auto given = [](bool is, double v) { return is ? std::optional<double>(v) : std::nullopt; };

  // Roughing (with a stock): the rough cutter, or the finishing one.
  const bool roughs = o.stock != "none";
  if (roughs) {
    const tooling::ToolChoice& rc = rough ? *rough : *finish;
    const double ap = o.step_down ? *o.step_down : o.rough_max_depth ? *o.rough_max_depth : default_depth(rc.geometry);
    const double ae = o.rough_stepover > 0 ? o.rough_stepover : 0.4 * rc.geometry.cutting_diameter();
    const auto f = feeds("roughing", rc, ap, ae, given(o.rpm_given, o.rpm), o.rough_feed);
    if (!o.rough_feed) o.rough_feed = f.feed;
    if (!o.rpm_given) o.rough_rpm = f.rpm;
  }
  // Finishing: after a roughing, the stock it leaves; without a stock, the tool's default depth.
  const double finish_ap = roughs && o.leave > 0 ? o.leave : default_depth(finish->geometry);
  const auto ff = feeds("finishing", *finish, finish_ap, o.stepover, given(o.rpm_given, o.rpm), given(o.feed_given, o.feed));
  if (!o.feed_given) o.feed = std::round(ff.feed);
  if (!o.rpm_given) o.rpm = std::round(ff.rpm);
  if (!o.plunge_feed_given) o.plunge_feed = std::round(ff.plunge_feed);
  if (rest) {
    const double ap = rest->geometry.cutting_diameter() / 2;
    const double ae = rest->geometry.cutting_diameter() / 2;
    const auto f = feeds("rest machining", *rest, ap, ae, given(o.rpm_given, o.rpm), given(o.feed_given, o.feed));
    o.rest_feed = std::round(f.feed);
    if (!o.rpm_given) o.rest_rpm = std::round(f.rpm);
  }
  if (o.rough_feed && !roughs) o.rough_feed.reset();
  if (o.rough_feed) o.rough_feed = std::round(*o.rough_feed);
  if (o.rough_rpm) o.rough_rpm = std::round(*o.rough_rpm);
  return plan;
}

std::string feeds_plan_text(const FeedsPlan& plan) {
  if (plan.operations.empty()) return {};
  std::string s = fmt::format("  feeds and speeds for {}:\n", plan.material);
  for (const auto& op : plan.operations) {
    const auto& f = op.feeds;
    s += fmt::format("    {:<14} {} {} flute{}, {:.3g} mm deep, {:.3g} mm wide (cuts {:.3g} mm across)\n", op.operation,
                     op.tool, op.flutes, op.flutes == 1 ? "" : "s", op.depth_of_cut, op.radial_engagement,
                     f.effective_diameter);
    s += fmt::format("      {:.0f} rpm ({}), feed {:.0f} mm/min ({})\n", f.rpm, f.rpm_from, f.feed, f.feed_from);
    s += fmt::format("      chip {:.4f} mm/tooth ({:.4f} mm feed per tooth), removal {:.2f} cm³/min\n", f.chip_load,
                     f.feed_per_tooth, f.removal_rate / 1000);
    for (const auto& w : f.warnings) s += fmt::format("      warning: {}\n", w);
  }
  return s;
}

std::string feeds_plan_text(const FeedsPlan& plan, const jobs::ToolpathProgram& program) {
  FeedsPlan used = plan;
  std::erase_if(used.operations, [&](const OperationFeeds& f) {
    return std::none_of(program.operations.begin(), program.operations.end(),
                        [&](const jobs::OperationSummary& op) { return op.name == f.operation; });
  });
  return feeds_plan_text(used);
}

}  // namespace cncstream::app
