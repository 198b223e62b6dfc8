#include "selection_options.hpp"

#include "tool_choice.hpp"

#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

namespace cncstream::app {

void add_selection_options(CLI::App* sub, SelectionOptions& o) {
  sub->add_option("stl", o.part.stl, "STL file")->required();
  add_part_options(sub, o.part);
  sub->add_option("--tools", o.tools,
                  "The ball and the radiused cutter, same diameter: ball:D,bull:D:r, or tools of the library by "
                  "number or name (3,4); a third (a tapered ball, taper:TIP_D:ANGLE:TOP_D) is cut on the same passes "
                  "beside them")
      ->capture_default_str();
  sub->add_option("--tool-library", o.tool_library,
                  "The tool library file (default: $CNCSTREAM_TOOLS, else tools.toml beside the journal)");
  sub->add_option("--stepover", o.stepover, "Distance between passes, mm")->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--step", o.step, "Sampling step along the passes, mm")->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--direction", o.direction, "Pass direction: x or y")->check(CLI::IsMember({"x", "y"}))->capture_default_str();
  sub->add_option("--scallop-tol", o.scallop_tol, "Scallop height accepted, mm (the plan cleans up above it)")
      ->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--reach-pitch", o.reach_pitch,
                  "CL lattice pitch for each cutter's reach limit, which splits material left into scallop and "
                  "unreachable (gaps narrower than the cutter), mm; 0: no split; default min(0.15, stepover/3)");
  // A oneTBB task arena of N slots for the whole job; 0: the shared pool.
  sub->add_option("--threads", o.threads, "Worker threads (0: all cores)");
  sub->add_flag("--nodes-csv", o.nodes_csv,
                "Also write nodes.csv: every CL point of the passes with both tip heights, d, slope and both choices "
                "(about 60 bytes a node)");
}

namespace {

// The pair, and a third cutter beside them if given.
void parse_cutters(const std::string& tools, const std::string& library, jobs::SelectionParams& p) {
  std::vector<cam::Cutter> cs;
  std::stringstream ss(tools);
  ToolLookup lookup(library);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) cs.push_back(cam::parse_cutter_spec(lookup.choose(item).spec()));
  if (cs.size() != 2 && cs.size() != 3)
    throw std::invalid_argument("--tools '" + tools +
                                "': give the ball and the radiused cutter, e.g. ball:3.175,bull:3.175:0.79, and "
                                "optionally a third, e.g. taper:1:5:3.175");
  if (cs[0].type != cam::CutterType::Ball) std::swap(cs[0], cs[1]);
  p.cutters = cam::CutterPair(cs[0], cs[1]);
  if (cs.size() == 3) p.tapered = cs[2];
}

}  // namespace

jobs::SelectionParams selection_params(const SelectionOptions& o) {
  jobs::SelectionParams p;
  parse_cutters(o.tools, o.tool_library, p);
  p.part = part_source(o.part);
  p.stepover = o.stepover;
  p.step = o.step;
  p.direction = o.direction == "y" ? cam::RasterDirection::Y : cam::RasterDirection::X;
  p.scallop_tol = o.scallop_tol;
  p.reach_pitch = o.reach_pitch;
  return p;
}

jobs::PlanParams plan_params(const SelectionOptions& o, std::string* feeds_report) {
  jobs::PlanParams p;
  p.selection = selection_params(o);
  p.feed = o.feed;
  p.plunge_feed = o.plunge_feed;
  p.rpm = o.rpm;
  p.max_rate = o.max_rate;
  p.accel = o.accel;
  if (!o.material.empty()) {
    // Each cutter as the finishing tool of a job without a stock (the plan
    // finishes from the part's top), within the machine's rate.
    std::string report;
    ToolLookup lookup(o.tool_library);
    const cam::Cutter* cutters[] = {&p.selection.cutters.ball, &p.selection.cutters.radiused};
    std::optional<jobs::PlanParams::CutterRate>* rates[] = {&p.ball_rate, &p.radiused_rate};
    for (int k = 0; k < 2; ++k) {
      jobs::ToolpathParams t;
      t.stepover = o.stepover;
      t.feed = o.feed;
      t.rpm = o.rpm;
      t.plunge_feed = o.plunge_feed;
      jobs::FeedsRequest q;
      q.material = o.material;
      const tooling::ToolChoice c = lookup.choose(cutters[k]->spec());
      q.finish = jobs::OperationTool{c.geometry, std::nullopt};
      q.limits.spindle_max = o.spindle_max;
      q.limits.max_feed_xy = o.max_rate;
      if (o.feed_given) q.feed = o.feed;
      if (o.rpm_given) q.rpm = o.rpm;
      if (o.plunge_feed_given) q.plunge_feed = o.plunge_feed;
      jobs::FeedsPlan plan = jobs::apply_material_feeds(t, q);
      *rates[k] = jobs::PlanParams::CutterRate{t.feed, t.plunge_feed, t.rpm};
      plan.operations.front().operation = k == 0 ? "ball" : "radiused";
      const std::string text = jobs::feeds_plan_text(plan);
      report += k == 0 ? text : text.substr(text.find('\n') + 1);
    }
    if (feeds_report) *feeds_report = report;
  }
  return p;
}

}  // namespace cncstream::app
