#include "toolpath_job.hpp"

#include <chrono>
#include <cmath>
#include <sstream>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/gcode/gcode_writer.hpp"
#include "job_display.hpp"

namespace cncstream::app {

void add_toolpath_options(CLI::App* sub, ToolpathOptions& o, bool tool_required) {
  add_part_options(sub, o.part);
  auto* tool = sub->add_option("--tool", o.tool, "Cutter: flat:D, ball:D, bull:D:r (mm; e.g. ball:3.175, ball:1/8in)");
  if (tool_required) tool->required();
  sub->add_option("--stepover", o.stepover, "Distance between rows, mm")->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--step", o.step, "Sampling step along a row, mm (default: min(stepover/4, 0.1))")->check(CLI::NonNegativeNumber);
  sub->add_option("--direction", o.direction, "Row direction: x or y")->check(CLI::IsMember({"x", "y"}))->capture_default_str();
  sub->add_option("--feed", o.feed, "Cutting feed, mm/min")->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--plunge-feed", o.plunge_feed, "Plunge feed, mm/min")->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--rpm", o.rpm, "Spindle speed (0: no spindle commands)")->check(CLI::NonNegativeNumber)->capture_default_str();
  sub->add_option("--safe-z", o.safe_z, "Retract height in work coordinates (default: 5 mm above the part top)");
  sub->add_option("--tolerance", o.tolerance, "Merge points on a line within this, mm (one-sided, never below the CL)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  sub->add_option("--bounds", o.bounds, "X0,Y0,X1,Y1 of the tool tip in model coordinates (default: part box grown by the tool radius)");
  sub->add_option("--floor", o.floor, "Lowest tip height in model coordinates (default: the part's lowest z)");
  sub->add_option("--origin", o.origin, "Work X0 Y0 at the part's XY minimum, its centre, or the model origin")
      ->check(CLI::IsMember({"min", "center", "model"}))->capture_default_str();
  sub->add_option("--z-zero", o.z_zero, "Work Z0 at the part's top, bottom, or the model origin")
      ->check(CLI::IsMember({"top", "bottom", "model"}))->capture_default_str();
  sub->add_option("--threads", o.threads, "Worker threads (0: all cores)");
}

ToolpathResult generate_toolpath(const ToolpathOptions& o) {
  ToolpathResult r;
  r.cutter = parse_cutter_spec(o.tool);
  auto t0 = std::chrono::steady_clock::now();
  const StlLoadResult part = load_part(o.part);
  r.facets = part.mesh.triangles.size();
  r.seconds_load = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  ClOptions clo;
  clo.floor = o.floor;
  clo.threads = o.threads;
  const ClEngine engine(part.mesh, r.cutter, clo);
  RasterOptions ro;
  ro.stepover = o.stepover;
  ro.step = o.step;
  ro.direction = o.direction == "y" ? RasterDirection::Y : RasterDirection::X;
  ro.tolerance = o.tolerance;
  XYBounds b = default_bounds(part.mesh, r.cutter);
  if (!o.bounds.empty()) {
    const auto v = parse_bounds(o.bounds);
    b = {v[0], v[1], v[2], v[3]};
  }
  const Box3 box = part.mesh.bounds();
  const XYOrigin xy = o.origin == "center" ? XYOrigin::PartCenter : o.origin == "model" ? XYOrigin::Model : XYOrigin::PartMin;
  const ZZero zz = o.z_zero == "bottom" ? ZZero::PartBottom : o.z_zero == "model" ? ZZero::Model : ZZero::PartTop;
  const Vec3 offset = work_offset(box, xy, zz);
  MachiningParams mp;
  // Path XY on the G-code's decimal lattice in work coordinates: printed = computed.
  ro.lattice = XYLattice{std::pow(10.0, -mp.decimals), -offset.x, -offset.y};
  r.path = build_raster(engine, b, ro);
  r.seconds_path = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  r.work_offset = offset;
  r.work_mesh = part.mesh;
  r.work_mesh.translate(offset);
  mp.feed = o.feed;
  mp.plunge_feed = o.plunge_feed;
  mp.rpm = o.rpm;
  mp.safe_z = o.safe_z.value_or(box.hi.z + offset.z + 5.0);
  std::ostringstream hdr;
  mp.header_comments = {
      "cncstream raster finishing",
      "part: " + o.part.stl + " (" + std::to_string(r.facets) + " facets)",
      "tool: " + r.cutter.description() + " [" + r.cutter.spec() + "]",
      "stepover " + format_gcode_number(r.path.stepover, 4) + " mm along " + (o.direction == "y" ? "Y" : "X") +
          ", step " + format_gcode_number(r.path.step, 4) + " mm, tolerance " + format_gcode_number(o.tolerance, 4) + " mm",
      std::string("work origin: XY at ") + (xy == XYOrigin::PartMin ? "part minimum" : xy == XYOrigin::PartCenter ? "part centre" : "model origin") +
          ", Z0 at " + (zz == ZZero::PartTop ? "part top" : zz == ZZero::PartBottom ? "part bottom" : "model origin"),
  };
  r.gcode = finishing_program(r.path, offset, mp, &r.stats);
  r.seconds_gcode = seconds_since(t0);
  return r;
}

std::string ToolpathResult::report() const {
  std::ostringstream o;
  const auto& b = stats.work_bounds;
  o << "tool: " << cutter.description() << " [" << cutter.spec() << "]\n";
  o << "rows: " << path.rows.size() << " at " << format_gcode_number(path.stepover, 4) << " mm, samples along rows every "
    << format_gcode_number(path.step, 4) << " mm (" << path.samples << " CL points incl. checks)\n";
  o << "points: " << path.points_before_merge << " sampled, " << path.points_after_merge
    << " after merging collinear points (";
  if (path.points_before_merge > 0)
    o << format_gcode_number(100.0 * (1.0 - double(path.points_after_merge) / double(path.points_before_merge)), 1)
      << " % fewer lines";
  o << ")\n";
  o << "G-code: " << stats.lines << " lines, cut " << format_gcode_number(stats.cut_length / 1000, 2) << " m, feed time "
    << format_duration(stats.feed_time_s) << " (no acceleration)\n";
  o << "tool tip in work coordinates: X " << format_gcode_number(b.lo.x) << " .. " << format_gcode_number(b.hi.x) << ", Y "
    << format_gcode_number(b.lo.y) << " .. " << format_gcode_number(b.hi.y) << ", Z " << format_gcode_number(b.lo.z) << " .. "
    << format_gcode_number(b.hi.z) << "\n";
  o << "time: load " << format_gcode_number(seconds_load, 3) << " s, CL + path " << format_gcode_number(seconds_path, 3)
    << " s, G-code " << format_gcode_number(seconds_gcode, 3) << " s\n";
  return o.str();
}

}  // namespace cncstream::app
