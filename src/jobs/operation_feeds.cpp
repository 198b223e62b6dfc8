#include "cncstream/jobs/operation_feeds.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace cncstream::jobs {

namespace detail_operation_feeds {

// The deepest cut a tool takes by default (default_max_depth's rule: half
// the diameter for a ball or bull-nose, a quarter for a flat; a V-bit or
// tapered ball: a quarter of its top).
double default_depth(const tooling::ToolGeometry& g) {
  const double d = g.cutting_diameter();
  return g.shape == tooling::ToolShape::Ball || g.shape == tooling::ToolShape::Bull ? d / 2 : d / 4;
}

}  // namespace detail_operation_feeds

std::string OperationTool::label() const {
  if (!tool) return fmt::format("[{}]", geometry.spec());
  return fmt::format("T{} {} [{}]", tool->number, tool->name, geometry.spec());
}

FeedsPlan apply_material_feeds(ToolpathParams& p, const FeedsRequest& q) {
  using detail_operation_feeds::default_depth;
  const tooling::Material& material = tooling::builtin_materials().find(q.material);
  FeedsPlan plan;
  plan.material = material.name == q.material ? material.name : fmt::format("{} ({})", material.name, q.material);
  auto feeds = [&](const char* operation, const OperationTool& t, double ap, double ae, std::optional<double> rpm,
                   std::optional<double> feed) {
    OperationFeeds f;
    f.operation = operation;
    f.tool = t.label();
    f.flutes = t.tool ? t.tool->flutes : q.spec_flutes;
    f.depth_of_cut = ap;
    f.radial_engagement = ae;
    tooling::CutRequest c;
    c.geometry = t.geometry;
    c.flutes = f.flutes;
    c.material = &material;
    if (t.tool) {
      c.tool_data = t.tool->cutting_for(q.material);
      if (!c.tool_data) c.tool_data = t.tool->cutting_for(material.name);
    }
    c.depth_of_cut = ap;
    c.radial_engagement = ae;
    c.rpm = rpm;
    c.feed = feed;
    c.limits = q.limits;
    f.feeds = tooling::compute_feeds(c);
    plan.operations.push_back(f);
    return f.feeds;
  };
  if (p.stock) {
    const OperationTool& rc = q.rough ? *q.rough : q.finish;
    const double ap = p.step_down ? *p.step_down : p.rough_max_depth ? *p.rough_max_depth : default_depth(rc.geometry);
    const double ae = p.rough_stepover > 0 ? p.rough_stepover : 0.4 * rc.geometry.cutting_diameter();
    const auto f = feeds("roughing", rc, ap, ae, q.rpm, q.rough_feed);
    if (!q.rough_feed) p.rough_feed = std::round(f.feed);
    if (!q.rpm) p.rough_rpm = std::round(f.rpm);
  }
  const double finish_ap = p.stock && p.leave > 0 ? p.leave : default_depth(q.finish.geometry);
  const auto ff = feeds("finishing", q.finish, finish_ap, p.stepover, q.rpm, q.feed);
  if (!q.feed) p.feed = std::round(ff.feed);
  if (!q.rpm) p.rpm = std::round(ff.rpm);
  if (!q.plunge_feed) p.plunge_feed = std::round(ff.plunge_feed);
  if (q.rest) {
    const double half = q.rest->geometry.cutting_diameter() / 2;
    const auto f = feeds("rest machining", *q.rest, half, half, q.rpm, q.feed);
    if (!q.feed) p.rest_feed = std::round(f.feed);
    if (!q.rpm) p.rest_rpm = std::round(f.rpm);
  }
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

std::string feeds_plan_text(const FeedsPlan& plan, const ToolpathProgram& program) {
  FeedsPlan used = plan;
  std::erase_if(used.operations, [&](const OperationFeeds& f) {
    return std::none_of(program.operations.begin(), program.operations.end(),
                        [&](const OperationSummary& op) { return op.name == f.operation; });
  });
  return feeds_plan_text(used);
}

}  // namespace cncstream::jobs
