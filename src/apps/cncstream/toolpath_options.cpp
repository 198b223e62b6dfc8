#include "toolpath_options.hpp"

#include <fmt/format.h>

#include <cmath>
#include <algorithm>
#include <sstream>

#include "cncsim/number_text.hpp"
#include "cncstream/gcode/gcode_writer.hpp"
#include "cncstream/protocol/link_model.hpp"
#include "job_display.hpp"

namespace cncstream::app {

void add_toolpath_options(CLI::App* sub, ToolpathOptions& o, bool tool_required) {
  add_part_options(sub, o.part);
  auto* tool = sub->add_option("--tool", o.tool,
                               "Cutter: a tool of the library by number or name (3, \"1/8 tapered ball\"), or a spec "
                               "flat:D, ball:D, bull:D:r (mm; e.g. ball:3.175, ball:1/8in)");
  if (tool_required) tool->required();
  sub->add_option("--stepover", o.stepover, "Distance between rows, mm")->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--step", o.step, "Sampling step along a row, mm (default: min(stepover/4, 0.1))")->check(CLI::NonNegativeNumber);
  sub->add_option("--direction", o.direction, "Row direction: x or y")->check(CLI::IsMember({"x", "y"}))->capture_default_str();
  sub->add_option("--strategy", o.strategy,
                  "Finishing: steep-shallow (rows where gentle, waterlines where steeper than --steep-angle) or raster "
                  "(rows over everything)")
      ->check(CLI::IsMember({"steep-shallow", "raster"}))->capture_default_str();
  sub->add_option("--steep-angle", o.steep_angle, "Where steep-shallow changes from rows to waterlines, degrees")
      ->check(CLI::Range(1.0, 89.0))->capture_default_str();
  sub->add_option("--scallop", o.scallop,
                  "Scallop height to keep, mm: sets the row stepover and the waterline step (ball or bull-nose; "
                  "replaces --stepover)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--rest", o.rest,
                  "Rest machining after the finishing with this smaller cutter, only where the finishing cutter cannot "
                  "reach (grooves, gaps, inside corners), e.g. ball:1");
  sub->add_option("--feed", o.feed, "Cutting feed, mm/min (default: from --material, else 1000)")
      ->check(CLI::PositiveNumber)->each([&o](const std::string&) { o.feed_given = true; });
  sub->add_option("--plunge-feed", o.plunge_feed, "Plunge feed, mm/min (default: from --material, else 300)")
      ->check(CLI::PositiveNumber)->each([&o](const std::string&) { o.plunge_feed_given = true; });
  sub->add_option("--rpm", o.rpm, "Spindle speed (0: no spindle commands; default: from --material, else 18000)")
      ->check(CLI::NonNegativeNumber)->each([&o](const std::string&) { o.rpm_given = true; });
  sub->add_option("--safe-z", o.safe_z, "Retract height in work coordinates (default: 5 mm above the part top)");
  sub->add_option("--tolerance", o.tolerance, "Merge points on a line within this, mm (one-sided, never below the CL)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  sub->add_option("--arcs", o.arcs,
                  "G2/G3 arcs where they fit within the tolerance less the controller's arc tolerance: on or off")
      ->check(CLI::IsMember({"on", "off"}))->capture_default_str();
  sub->add_option("--controller-arc-tolerance", o.controller_arc_tolerance,
                  "The controller's arc tolerance (GRBL $12): the chords it cuts an arc with sag this much, mm")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  sub->add_option("--bounds", o.bounds, "X0,Y0,X1,Y1 of the tool tip in model coordinates (default: part box grown by the tool radius)");
  sub->add_option("--floor", o.floor, "Lowest tip height in model coordinates (default: the part's lowest z)");
  sub->add_option("--origin", o.origin, "Work X0 Y0 at the part's XY minimum, its centre, or the model origin")
      ->check(CLI::IsMember({"min", "center", "model"}))->capture_default_str();
  sub->add_option("--z-zero", o.z_zero, "Work Z0 at the part's top, bottom, or the model origin")
      ->check(CLI::IsMember({"top", "bottom", "model"}))->capture_default_str();
  // A oneTBB task arena of N slots for the whole job; 0: the shared pool.
  sub->add_option("--threads", o.threads, "Worker threads (0: all cores)");

  const char* group = "Stock and depth of cut";
  sub->add_option("--stock", o.stock,
                  "The stock: auto (the part's box grown by 1 mm at the sides and top), auto:MARGIN, a block "
                  "X0,Y0,Z0:X1,Y1,Z1 in work coordinates, a height map from `cncsim --result` (FILE.f32), or none "
                  "(finish only, from the part's top, no depth check)")
      ->capture_default_str()->group(group);
  sub->add_option("--work-origin", o.work_origin,
                  "X,Y,Z: this job's work zero in machine coordinates (G54 + G92, as $# shows them), to place a "
                  "--stock FILE.f32 saved with its own work origin where it physically is (PORT=sim without "
                  "--sim-settings: 0,0,0)")
      ->group(group);
  sub->add_option("--max-depth", o.max_depth,
                  "Deepest cut the finishing cutter takes in one pass, mm (default: half the diameter for ball and "
                  "bull, a quarter for flat); deeper, the job roughs first")
      ->check(CLI::PositiveNumber)->group(group);
  sub->add_option("--rough", o.rough, "Roughing cutter (default: the finishing cutter), e.g. flat:6")->group(group);
  sub->add_option("--rough-max-depth", o.rough_max_depth, "Deepest cut of the roughing cutter, mm (default as --max-depth)")
      ->check(CLI::PositiveNumber)->group(group);
  sub->add_option("--leave", o.leave, "Stock the roughing leaves on the part, mm")
      ->check(CLI::NonNegativeNumber)->capture_default_str()->group(group);
  sub->add_option("--step-down", o.step_down,
                  "Roughing levels at most this far apart, mm (default: within both cutters' depths)")
      ->check(CLI::PositiveNumber)->group(group);
  sub->add_option("--rough-stepover", o.rough_stepover, "Roughing stepover, mm (default: 40 % of its diameter)")
      ->check(CLI::NonNegativeNumber)->group(group);
  sub->add_option("--rough-feed", o.rough_feed, "Roughing feed, mm/min (default: --feed)")
      ->check(CLI::PositiveNumber)->group(group);
  sub->add_option("--link-rate", o.link_rate,
                  "The link the program streams over: bytes/s (11520), a baud rate (115200baud) or 'usb' (default: "
                  "the machine's; GRBL 1.1's 115200baud without one); where a stretch of moves cannot arrive in "
                  "time at its feed, F is lowered there, and the plan says so")
      ->group(group);
  const char* feeds = "Tool library, feeds and speeds";
  sub->add_option("--material", o.material,
                  "Compute rpm and feeds per operation from chip load for this material (walnut, maple, pine, mdf, "
                  "plywood, acrylic, hdpe, aluminium, brass ...); --feed, --rpm, --plunge-feed and --rough-feed win")
      ->group(feeds);
  sub->add_option("--tool-library", o.tool_library,
                  "The tool library file (default: $CNCSTREAM_TOOLS, else tools.toml beside the journal)")
      ->group(feeds);
  sub->add_option("--flutes", o.flutes, "Flutes of a tool given as a spec (default 2; a library tool has its own)")
      ->check(CLI::Range(1, 12))->group(feeds);
  sub->add_option("--spindle-max", o.spindle_max, "The spindle's highest speed, rpm ($30): computed rpm stays within it")
      ->check(CLI::NonNegativeNumber)->capture_default_str()->group(feeds);
  sub->add_option("--spindle-min", o.spindle_min, "The spindle's lowest speed, rpm ($31)")
      ->check(CLI::NonNegativeNumber)->capture_default_str()->group(feeds);
  sub->add_option("--max-feed", o.max_feed,
                  "The machine's highest X/Y rate, mm/min ($110/$111): computed feeds stay within it (0: the "
                  "controller's, where the command knows it)")
      ->check(CLI::NonNegativeNumber)->group(feeds);
  sub->add_option("--tool-change", o.tool_change,
                  "How the program pauses for a tool change: m0 (GRBL: a pause and a comment) or m6")
      ->check(CLI::IsMember({"m0", "m6"}))->capture_default_str()->group(group);
}

jobs::ToolpathParams toolpath_params(const ToolpathOptions& o) {
  jobs::ToolpathParams p;
  p.cutter = cam::parse_cutter_spec(o.tool);
  p.part = part_source(o.part);
  p.stepover = o.stepover;
  p.step = o.step;
  p.direction = o.direction == "y" ? cam::RasterDirection::Y : cam::RasterDirection::X;
  p.strategy = o.strategy == "raster" ? jobs::FinishStrategy::Raster : jobs::FinishStrategy::SteepShallow;
  p.steep_angle = o.steep_angle;
  p.scallop = o.scallop;
  p.feed = o.feed;
  p.plunge_feed = o.plunge_feed;
  p.rpm = o.rpm;
  p.safe_z = o.safe_z;
  p.tolerance = o.tolerance;
  p.arcs = o.arcs == "on";
  p.controller_arc_tolerance = o.controller_arc_tolerance;
  if (!o.bounds.empty()) {
    const auto v = parse_bounds(o.bounds);
    p.bounds = cam::XYBounds{v[0], v[1], v[2], v[3]};
  }
  p.floor = o.floor;
  p.origin = o.origin == "center" ? XYOrigin::PartCenter : o.origin == "model" ? XYOrigin::Model : XYOrigin::PartMin;
  p.z_zero = o.z_zero == "bottom" ? ZZero::PartBottom : o.z_zero == "model" ? ZZero::Model : ZZero::PartTop;
  if (o.stock != "none") p.stock = jobs::parse_stock_spec(o.stock);
  if (!o.work_origin.empty()) {
    const auto v = cncsim::vec3_from(o.work_origin);
    if (!v) throw std::invalid_argument("--work-origin '" + o.work_origin + "': expected X,Y,Z (machine mm)");
    if (p.stock) p.stock->work_origin = *v;
  }
  p.max_depth = o.max_depth;
  if (!o.rough.empty()) p.rough = cam::parse_cutter_spec(o.rough);
  if (!o.rest.empty()) p.rest = cam::parse_cutter_spec(o.rest);
  p.rough_max_depth = o.rough_max_depth;
  p.leave = o.leave;
  p.step_down = o.step_down;
  p.rough_stepover = o.rough_stepover;
  p.rough_feed = o.rough_feed;
  p.tool_change = o.tool_change == "m6" ? ToolChangeCode::M6 : ToolChangeCode::PauseM0;
  // The program is fitted to the link it will stream over: GRBL 1.1's 115,200
  // baud unless --link-rate says otherwise ('usb': unbounded, F never lowered).
  // The main command replaces it with the machine's own (planning_link).
  gcode::StreamLink link = protocol::grbl_default_link();
  if (!o.link_rate.empty()) link.bytes_per_second = protocol::parse_link_rate(o.link_rate);
  p.link = link;
  if (!p.stock && (p.rough || p.max_depth || p.step_down))
    throw std::invalid_argument("--stock none finishes from the part's top without a depth check: --rough, "
                                "--max-depth and --step-down need a stock");
  return p;
}

std::string operations_text(const jobs::ToolpathProgram& r, const EtaEstimator* eta) {
  std::ostringstream o;
  for (std::size_t k = 0; k < r.operations.size(); ++k) {
    const auto& op = r.operations[k];
    // From its first line to the next one's (the last: to the program's end).
    const long first = k == 0 ? 1 : static_cast<long>(op.first_line);
    const long last = k + 1 < r.operations.size() ? static_cast<long>(r.operations[k + 1].first_line) - 1
                                                   : static_cast<long>(r.stats.lines);
    const double seconds = eta ? eta->at_line(last) - eta->at_line(first - 1) : op.feed_time_s;
    o << fmt::format("  {}. {:<10} T{} {:<14} {:>9} lines  {:>9}{}  {}\n", k + 1, op.name, op.tool, op.cutter.spec(),
                     last - first + 1, format_duration(seconds), eta ? "" : " at feed", op.detail);
    if (op.link_checked)
      o << (std::isinf(op.wire_feed) ? std::string("     the wire allows any feed here")
                                     : fmt::format("     the wire allows {:.0f} mm/min here", op.wire_feed))
        << fmt::format("; {:.1f} % of its path runs below the commanded feed\n", 100.0 * op.share_below_feed);
  }
  for (const auto& n : r.notes) o << "  " << n << "\n";
  return o.str();
}

std::string toolpath_report(const jobs::ToolpathProgram& r) {
  const auto& cutter = r.cutter;
  const auto& path = r.path;
  const auto& stats = r.stats;
  std::ostringstream o;
  const auto& b = stats.work_bounds;
  o << "tool: " << cutter.description() << " [" << cutter.spec() << "]\n";
  o << "rows: " << path.rows.size() << " at " << jobs::row_spacing_text(path) << " mm, samples along rows every "
    << format_gcode_number(path.step, 4) << " mm (" << path.samples << " CL points incl. checks)\n";
  o << "points: " << path.points_before_merge << " sampled, " << path.points_after_merge
    << " after merging collinear points (";
  if (path.points_before_merge > 0)
    o << format_gcode_number(100.0 * (1.0 - double(path.points_after_merge) / double(path.points_before_merge)), 1)
      << " % fewer lines";
  o << ")\n";
  const bool wire_checked = !r.operations.empty() && r.operations.front().link_checked;
  if (r.operations.size() > 1 || !r.notes.empty() || wire_checked) o << "operations:\n" << operations_text(r);
  o << "G-code: " << stats.lines << " lines (" << stats.arcs << " arcs), cut " << format_gcode_number(stats.cut_length / 1000, 2) << " m, feed time "
    << format_duration(stats.feed_time_s) << " (no acceleration)\n";
  o << "tool tip in work coordinates: X " << format_gcode_number(b.lo.x) << " .. " << format_gcode_number(b.hi.x) << ", Y "
    << format_gcode_number(b.lo.y) << " .. " << format_gcode_number(b.hi.y) << ", Z " << format_gcode_number(b.lo.z) << " .. "
    << format_gcode_number(b.hi.z) << "\n";
  o << "time: load " << format_gcode_number(r.seconds_load, 3) << " s, CL + path " << format_gcode_number(r.seconds_path, 3);
  if (r.seconds_rest > 0) o << " s, rest machining " << format_gcode_number(r.seconds_rest, 3);
  if (r.seconds_rough > 0) o << " s, roughing " << format_gcode_number(r.seconds_rough, 3);
  o << " s, G-code " << format_gcode_number(r.seconds_gcode, 3) << " s";
  if (r.stages_overlap) o << " (the roughing's path and the rest machining ran beside the CL + path)";
  o << "\n";
  return o.str();
}

}  // namespace cncstream::app
