#include "job_operations.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/path_machining.hpp"
#include "cncstream/cam/pass_depth.hpp"
#include "cncstream/gcode/roughing_program.hpp"

namespace cncstream::jobs {

OperationSummary finishing_summary(const ToolpathProgram& r, const ToolpathParams& p, const ProgramStats& stats) {
  OperationSummary o;
  o.name = "finishing";
  o.cutter = r.cutter;
  o.detail = fmt::format("raster, {} rows {} mm apart along {}", r.path.rows.size(), row_spacing_text(r.path),
                         p.direction == cam::RasterDirection::Y ? "Y" : "X");
  if (r.waterline_pieces > 0)
  {
    const std::string apart = r.waterline_step_max > r.waterline_step + 5e-5
                                  ? fmt::format("{} to {}", format_gcode_number(r.waterline_step, 4),
                                                format_gcode_number(r.waterline_step_max, 4))
                                  : format_gcode_number(r.waterline_step, 4);
    o.detail = fmt::format("waterlines where steeper than {} degrees ({} levels {} mm apart, {} pieces), then {} with "
                           "{} steep stretches left to them",
                           format_gcode_number(p.steep_angle, 1), r.waterline_levels, apart, r.waterline_pieces,
                           o.detail, r.steep_bridges);
  }
  o.lines = stats.lines;
  o.cut_length = stats.cut_length;
  o.feed_time_s = stats.feed_time_s;
  return o;
}

std::vector<int> job_tool_numbers(const std::vector<std::optional<int>>& library_numbers) {
  std::set<int> taken;
  for (const auto& n : library_numbers)
    if (n) taken.insert(*n);
  std::vector<int> out;
  for (std::size_t k = 0; k < library_numbers.size(); ++k) {
    if (library_numbers[k]) {
      out.push_back(*library_numbers[k]);
      continue;
    }
    int n = static_cast<int>(k) + 1;
    while (taken.count(n)) ++n;
    taken.insert(n);
    out.push_back(n);
  }
  return out;
}

void compose_job(ToolpathProgram& r, const ToolpathParams& p, const RoughingStage* with_stock, const RestStage* rest,
                 MachiningParams mp) {
  static const RoughingStage kNoStock;
  const RoughingStage& rough = with_stock ? *with_stock : kNoStock;
  r.notes = rough.notes;
  JobProgramOptions jo;
  jo.header_comments = mp.header_comments;
  if (with_stock) {
    r.stock = rough.stock.box;
    // Rapids and tool changes above the stock, not only the part.
    const double stock_top = rough.stock.box.hi.z;
    if (!p.safe_z) {
      mp.safe_z = std::max(mp.safe_z, stock_top + 5.0);
    } else if (!(*p.safe_z > stock_top + 0.5)) {
      throw std::invalid_argument(fmt::format("safe Z {} is not at least 0.5 mm above the stock's top Z {} (work "
                                              "coordinates)",
                                              format_gcode_number(*p.safe_z), format_gcode_number(stock_top)));
    }
    jo.header_comments.insert(jo.header_comments.begin() + 1,
                              fmt::format("stock: X {:.3f}..{:.3f} Y {:.3f}..{:.3f} Z {:.3f}..{:.3f} (work coordinates)",
                                          rough.stock.box.lo.x, rough.stock.box.hi.x, rough.stock.box.lo.y,
                                          rough.stock.box.hi.y, rough.stock.box.lo.z, rough.stock.box.hi.z));
  }
  jo.decimals = mp.decimals;
  jo.safe_z = mp.safe_z;
  jo.dwell_s = mp.dwell_s;
  jo.tool_change = p.tool_change;
  {
    const char* finishing = r.waterline_pieces > 0 ? "steep-and-shallow finishing" : "raster finishing";
    const std::string then_rest = rest && !rest->pieces.empty() ? ", then rest machining" : "";
    jo.header_comments.front() =
        !rough.rest.empty() ? fmt::format("cncstream job: Z-level roughing, rest roughing, then {}{}", finishing, then_rest)
        : rough.path        ? fmt::format("cncstream job: Z-level roughing, then {}{}", finishing, then_rest)
                            : fmt::format("cncstream job: {}{}", finishing, then_rest);
  }
  if (rest) {
    const std::string note =
        rest->pieces.empty()
            ? fmt::format("rest machining with the {}: the {} leaves nothing more than {} mm it could take",
                          rest->cutter.spec(), p.cutter.spec(), format_gcode_number(rest->threshold, 3))
            : fmt::format("rest machining with the {} where the {} cannot reach: {} pieces of rows {} mm apart over "
                          "{} analysis nodes where it leaves more than {} mm (up to {} mm)",
                          rest->cutter.spec(), p.cutter.spec(), rest->pieces.size(),
                          format_gcode_number(rest->stepover, 3), rest->nodes, format_gcode_number(rest->threshold, 3),
                          format_gcode_number(rest->most_left, 3));
    r.notes.push_back(note);
  }
  for (const auto& n : r.notes) jo.header_comments.push_back(n);
  JobProgram program(jo);

  // An operation's lines and time begin with its tool change.
  auto begin = [&](const std::string& name, int tool, const cam::Cutter& c, double rpm) {
    auto at = std::make_pair(program.writer().lines().size(), program.stats());
    program.begin_operation({name, tool, c, rpm});
    return at;
  };
  auto summary = [&](OperationSummary o, const std::pair<std::size_t, ProgramStats>& at) {
    o.first_line = at.first + 1;
    o.lines = program.writer().lines().size() - at.first;
    o.cut_length = program.stats().cut_length - at.second.cut_length;
    o.feed_time_s = program.stats().feed_time_s - at.second.feed_time_s;
    r.operations.push_back(std::move(o));
  };

  // The program's cutters in order, with their library numbers: the
  // roughing's (unless the finishing cutter roughs), the finishing's (rest
  // roughing and finishing), the rest machining's.
  const bool rough_changes = rough.path && rough.path->cutter.spec() != p.cutter.spec();
  const bool rest_cuts = rest && !rest->pieces.empty();
  // A roughing with the finishing's own cutter: whichever names its library tool.
  const std::optional<int> finish_number =
      p.tool_number ? p.tool_number : rough.path && !rough_changes ? p.rough_tool_number : std::nullopt;
  std::vector<std::optional<int>> numbered;
  if (rough_changes) numbered.push_back(p.rough_tool_number);
  numbered.push_back(finish_number);
  if (rest_cuts) numbered.push_back(p.rest_tool_number);
  const std::vector<int> numbers = job_tool_numbers(numbered);
  std::size_t next_number = 0;
  int tool = numbers[next_number++];
  if (rough.path) {
    const auto at = begin("roughing", tool, rough.path->cutter, p.rough_rpm.value_or(p.rpm));
    MachiningParams rm = mp;
    rm.feed = p.rough_feed.value_or(p.feed);
    rm.rpm = p.rough_rpm.value_or(p.rpm);
    write_roughing(program.writer(), *rough.path, r.work_offset, rm, program.stats());
    OperationSummary o;
    o.name = "roughing";
    o.tool = tool;
    o.cutter = rough.path->cutter;
    o.detail = fmt::format("Z-level, {} levels, stepover {} mm, leave {} mm", rough.path->levels.size(),
                           format_gcode_number(rough.path->stepover, 3), format_gcode_number(p.leave, 3));
    o.max_depth = rough.rough_max_depth;
    o.depth_limit = o.max_depth;
    o.rpm = rm.rpm;
    o.feed = rm.feed;
    summary(std::move(o), at);
    // The same cutter finishes without a tool change.
    if (rough_changes) tool = numbers[next_number++];
  }
  if (!rough.rest.empty()) {
    // With the finishing cutter: the finishing follows without a tool change.
    const auto at = begin("rest roughing", tool, p.cutter, p.rpm);
    std::size_t levels = 0;
    for (const auto& rest : rough.rest) {
      write_roughing(program.writer(), rest, r.work_offset, mp, program.stats());
      levels += rest.levels.size();
    }
    OperationSummary o;
    o.name = "rest roughing";
    o.tool = tool;
    o.cutter = p.cutter;
    o.detail = fmt::format("Z-level where the roughing cutter could not reach and the finishing would cut too deep "
                           "(near {} points of its moves too deep), {} levels, stepover {} mm, leave {} mm",
                           rough.rest_spots, levels, format_gcode_number(rough.rest.front().stepover, 3),
                           format_gcode_number(rough.rest_leave, 3));
    o.max_depth = rough.rest_step_down;
    o.depth_limit = o.max_depth;
    o.rpm = p.rpm;
    o.feed = mp.feed;
    summary(std::move(o), at);
  }
  const auto at = begin("finishing", tool, p.cutter, p.rpm);
  write_pieces(program.writer(), r.finish_pieces, r.work_offset, mp, program.stats());
  OperationSummary f = finishing_summary(r, p, ProgramStats{});
  f.tool = tool;
  f.max_depth = rough.finish_depth;
  if (with_stock) f.depth_limit = finishing_depth_limit(rough, p);
  f.rpm = p.rpm;
  f.feed = mp.feed;
  summary(std::move(f), at);
  if (rest_cuts) {
    tool = numbers[next_number++];
    const auto at_rest = begin("rest machining", tool, rest->cutter, p.rest_rpm.value_or(p.rpm));
    MachiningParams restp = mp;
    restp.feed = p.rest_feed.value_or(p.feed);
    restp.rpm = p.rest_rpm.value_or(p.rpm);
    OperationSummary o;
    o.name = "rest machining";
    o.tool = tool;
    o.cutter = rest->cutter;
    std::size_t levels = 0;
    for (const auto& l : rest->levels) {
      write_roughing(program.writer(), l, r.work_offset, restp, program.stats());
      levels += l.levels.size();
    }
    o.detail = fmt::format("{}rows {} mm apart where the {} cannot reach ({} pieces), {} pencil passes along the "
                           "creases there",
                           levels ? fmt::format("Z-levels where it would cut too deep in one pass ({} levels, leave {} "
                                                "mm), then ",
                                                levels, format_gcode_number(rest->level_leave, 3))
                                  : "",
                           format_gcode_number(rest->stepover, 3), p.cutter.spec(),
                           rest->pieces.size() - rest->pencils, rest->pencils);
    write_pieces(program.writer(), rest->pieces, r.work_offset, restp, program.stats());
    o.max_depth = rest->depth;
    o.depth_limit = o.max_depth;
    o.rpm = restp.rpm;
    o.feed = restp.feed;
    summary(std::move(o), at_rest);
  }
  r.gcode = program.finish();
  r.stats = program.stats();
}

}  // namespace cncstream::jobs
