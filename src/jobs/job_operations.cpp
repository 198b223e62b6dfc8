#include "job_operations.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/path_machining.hpp"
#include "cncstream/cam/pass_depth.hpp"
#include "cncstream/gcode/roughing_program.hpp"

namespace cncstream::jobs {

namespace {

// The deepest the pass cuts below the stock's top: over its points whose
// cutter reaches over the stock (work coordinates).
double depth_below_stock(const std::vector<Polyline>& pieces, const Vec3& offset, const WorkStock& stock,
                         double radius) {
  double deepest = 0;
  auto visit = [&](const Polyline& pl) {
    for (const Vec3& m : pl) {
      const Vec3 v = m + offset;
      if (v.x < stock.box.lo.x - radius || v.x > stock.box.hi.x + radius || v.y < stock.box.lo.y - radius ||
          v.y > stock.box.hi.y + radius)
        continue;
      const double x = std::clamp(v.x, stock.box.lo.x, stock.box.hi.x);
      const double y = std::clamp(v.y, stock.box.lo.y, stock.box.hi.y);
      deepest = std::max(deepest, stock.top_at(x, y) - v.z);
    }
  };
  for (const auto& piece : pieces) visit(piece);
  return deepest;
}

// A height map in work coordinates as a stock surface in model coordinates
// (no value: the block's top).
HeightFieldStock model_surface(const HeightFieldData& map, const Vec3& work_offset, double top) {
  GridSpec g = map.grid;
  g.x0 -= work_offset.x;
  g.y0 -= work_offset.y;
  std::vector<double> z(map.z.size());
  for (std::size_t n = 0; n < z.size(); ++n)
    z[n] = std::isfinite(map.z[n]) ? static_cast<double>(map.z[n]) - work_offset.z : top;
  return HeightFieldStock(g, top, std::move(z));
}

std::string mm(double v) { return fmt::format("{:.2f} mm", v); }

// The stock before the roughing on a grid over the block (model
// coordinates): the block's top, or the height map's surface below it.
HeightFieldStock stock_before(const StockBlock& block, double cell) {
  const GridSpec g = GridSpec::covering(block.x0, block.y0, block.x1, block.y1, cell, cell);
  std::vector<double> z(g.size(), block.top);
  if (block.surface)
    for (std::size_t j = 0; j < g.ny; ++j)
      for (std::size_t i = 0; i < g.nx; ++i)
        if (const double h = stock_height_at(*block.surface, g.x(i), g.y(j)); std::isfinite(h))
          z[j * g.nx + i] = std::min(h, block.top);
  return HeightFieldStock(g, block.top, std::move(z));
}

// The rest roughing's leave: small, so the ball grown by it fits gaps
// barely wider than the ball (the roughing's 0.3 mm would make a 3.175 mm
// ball 3.775 mm wide, as wide as the gaps it is for); enough to hold what the
// rest roughing's own chords take (half its 0.05 mm region tolerance) and
// the program's arcs (its tolerance), so nothing is gouged and the
// finishing pass has a skin to cut. A gap between the ball's width and the
// grown ball's is left to the finishing: the measure after says whether
// that is within its depth. (On the plaque 0.02 mm, at a 0.02 mm tolerance,
// cut as deep a finish with twice the lines.) No more than asked.
constexpr double kRestLeave = 0.05;

}  // namespace

double round_stepover(const Cutter& c, double step_down) {
  const double t = std::min(c.corner_radius, step_down / 4);
  const double reach =
      c.core_radius() + std::sqrt(c.corner_radius * c.corner_radius - (c.corner_radius - t) * (c.corner_radius - t));
  return std::clamp(reach - c.radius / 6, 0.1 * c.diameter(), 0.4 * c.diameter());
}

HeightFieldStock stock_after(const HeightFieldStock& stock, const RoughingPath& path) {
  std::vector<double> z = machine_path(stock.grid(), stock.heights(), {roughing_moves(path)}, path.cutter);
  return HeightFieldStock(stock.grid(), stock.top(), std::move(z));
}

RoughingStage plan_roughing(const ToolpathParams& p, const Mesh& mesh, const std::vector<Polyline>& finishing,
                            const Vec3& work_offset, const Checkpoint& checkpoint) {
  RoughingStage s;
  Box3 part = mesh.bounds();
  part.lo = part.lo + work_offset;
  part.hi = part.hi + work_offset;
  s.stock = resolve_stock(*p.stock, part);
  s.finish_max_depth = p.max_depth.value_or(default_max_depth(p.cutter));
  if (!(s.finish_max_depth > 0)) throw std::invalid_argument("the maximum depth of cut must be positive");
  s.finish_depth_alone = depth_below_stock(finishing, work_offset, s.stock, p.cutter.radius);
  s.finish_depth = s.finish_depth_alone;
  const bool needed = s.finish_depth_alone > s.finish_max_depth + 1e-9;
  if (!needed && !p.rough) {
    s.notes.push_back(fmt::format("the finishing pass cuts at most {} below the stock's top, within its cutter's {}: "
                                  "no roughing",
                                  mm(s.finish_depth_alone), mm(s.finish_max_depth)));
    return s;
  }
  const Cutter rc = p.rough.value_or(p.cutter);
  s.rough_max_depth = p.rough_max_depth.value_or(default_max_depth(rc));
  if (!(s.rough_max_depth > 0)) throw std::invalid_argument("the roughing cutter's maximum depth must be positive");
  if (!(p.leave >= 0)) throw std::invalid_argument("the stock to leave must not be negative");
  if (!(p.leave < s.finish_max_depth))
    throw std::invalid_argument(fmt::format("the stock to leave ({}) is not less than the finishing cutter's maximum depth "
                                            "({}): the finishing pass could not take it",
                                            mm(p.leave), mm(s.finish_max_depth)));
  if (needed)
    s.notes.push_back(fmt::format("the finishing pass alone would cut {} deep in one pass, more than the {}'s {}: "
                                  "roughing first with the {}",
                                  mm(s.finish_depth_alone), p.cutter.spec(), mm(s.finish_max_depth), rc.spec()));
  else
    s.notes.push_back(fmt::format("roughing with the {} as asked", rc.spec()));

  // The stock as a block in model coordinates; a height map its surface
  // (levels start below its highest point and cut only where there is
  // material above them).
  StockBlock block;
  block.x0 = s.stock.box.lo.x - work_offset.x;
  block.y0 = s.stock.box.lo.y - work_offset.y;
  block.x1 = s.stock.box.hi.x - work_offset.x;
  block.y1 = s.stock.box.hi.y - work_offset.y;
  block.top = s.stock.box.hi.z - work_offset.z;
  if (s.stock.heights) {
    s.surface = std::make_shared<const HeightFieldStock>(model_surface(*s.stock.heights, work_offset, block.top));
    block.surface = s.surface.get();
  }

  RoughingParams rp;
  rp.leave = p.leave;
  // No level below the stock's bottom (an open mesh would let the tip go
  // below the part's floor).
  rp.bottom = s.stock.box.lo.z - work_offset.z;
  rp.stepover = p.rough_stepover;
  if (!(rp.stepover > 0) && rc.corner_radius > 0) {
    // A round end leaves scallops between its loops that the next level
    // must take as well: loops close enough that they stay under a quarter
    // of the step-down (the roughing allows for a further grid cell, at most
    // a sixth of the radius).
    rp.stepover = round_stepover(rc, p.step_down.value_or(std::min(s.rough_max_depth, s.finish_max_depth - p.leave)));
  }
  // Every roughing pass within the roughing cutter's depth, and what the
  // terraces leave within the finishing cutter's.
  rp.step_down = p.step_down.value_or(std::min(s.rough_max_depth, s.finish_max_depth - p.leave));
  if (!(rp.step_down > 0) || rp.step_down > s.rough_max_depth + 1e-9)
    throw std::invalid_argument(fmt::format("step-down {} must be positive and at most the roughing cutter's maximum "
                                            "depth {}",
                                            mm(rp.step_down), mm(s.rough_max_depth)));
  ClOptions clo;
  clo.floor = p.floor;
  const ClEngine grown(mesh, grown_cutter(rc, p.leave), clo);
  RoughingPath path = build_zlevel_roughing(grown, rc, block, rp, checkpoint);
  // The terraces' bound came out above what the finishing cutter may take
  // (round cutters leave scallops between loops too): once more with the
  // levels closer by the excess.
  double after = p.leave + path.terrace_bound;
  if (after > s.finish_max_depth + 1e-9 && !p.step_down) {
    rp.step_down -= after - s.finish_max_depth;
    if (rp.step_down > 0.05) {
      path = build_zlevel_roughing(grown, rc, block, rp, checkpoint);
      after = p.leave + path.terrace_bound;
    }
  }
  s.notes.push_back(fmt::format("roughing: {} levels, step-down at most {}, stepover {}, leaving {} (terraces up to {} more)",
                                path.levels.size(), mm(rp.step_down), mm(path.stepover), mm(p.leave),
                                mm(path.terrace_bound)));
  s.path = std::move(path);

  // The finishing pass cut into the stock the roughing leaves (a height
  // map fine enough for the finishing cutter): where the roughing cutter
  // could not reach (gaps narrower than it grown by the leave), it would
  // still cut deep. Its depth of cut leaves out a rim as wide as the leave:
  // its side cut of the skin along a wall is as tall as the wall.
  const double cell = std::min(0.25, p.cutter.radius / 4);
  const double retract_z = block.top + 1;
  auto finishing_depth = [&](const HeightFieldStock& stock) {
    return pass_depth(stock, finishing, p.cutter, p.leave, s.finish_max_depth, retract_z);
  };
  auto where = [&](const PassDepth& e) {
    return fmt::format("X{:.3f} Y{:.3f} (work coordinates; down to Z{:.3f})", e.at.x + work_offset.x,
                       e.at.y + work_offset.y, e.at.z + work_offset.z);
  };
  const HeightFieldStock roughed = stock_after(stock_before(block, cell), *s.path);
  const PassDepth after_rough = finishing_depth(roughed);
  s.finish_depth = after_rough.deepest;
  if (after_rough.deepest <= s.finish_max_depth + 1e-9) {
    s.notes.push_back(fmt::format("after roughing the finishing pass cuts at most {}, within its cutter's {}",
                                  mm(after_rough.deepest), mm(s.finish_max_depth)));
    return s;
  }

  // Rest roughing with the finishing cutter (no tool change before the
  // finishing) near where it would cut too deep, from the roughed stock:
  // levels only where material stands above them, each within the
  // finishing cutter's depth, and one that brings the stock there within it.
  s.rest_spots = after_rough.over.size();
  RoughingParams rr;
  rr.tolerance = 0.05;
  rr.leave = std::min(p.leave, std::max(kRestLeave, rr.tolerance / 2 + p.tolerance));
  rr.bottom = rp.bottom;
  rr.near = after_rough.over;
  // The cutter over a spot from anywhere it can lower it (the window is a
  // grid cell wider).
  rr.near_radius = p.cutter.radius;
  rr.step_down = s.finish_max_depth - rr.leave;
  if (p.cutter.corner_radius > 0) rr.stepover = round_stepover(p.cutter, rr.step_down);
  StockBlock rest_block = block;
  const ClEngine grown_finish(mesh, grown_cutter(p.cutter, rr.leave), clo);
  // The stage's progress stays where the roughing ended; a stop request
  // still stops it.
  Checkpoint rest_checkpoint;
  if (checkpoint) rest_checkpoint = [&checkpoint](double) { checkpoint(1.0); };
  // What a rest roughing leaves too deep (its regions come from a grid: a
  // pit the finishing ball drops into, narrower than a cell, is missed) gets
  // another near it alone, from the stock after it, on a grid half as fine.
  HeightFieldStock stock = roughed;
  PassDepth depth = after_rough;
  double grid_step = 0;  // the roughing's default first
  for (int attempt = 1;; ++attempt) {
    rest_block.surface = &stock;
    rr.grid_step = grid_step;
    RoughingPath rest = build_zlevel_roughing(grown_finish, p.cutter, rest_block, rr, rest_checkpoint);
    if (rest.levels.empty())
      throw std::invalid_argument(fmt::format(
          "after roughing{} the finishing pass would still cut {} at {}, more than the {}'s {}, and a rest roughing "
          "with it finds nothing it can cut there: give a smaller --leave or --step-down",
          s.rest.empty() ? "" : " and rest roughing", mm(depth.deepest), where(depth), p.cutter.spec(),
          mm(s.finish_max_depth)));
    HeightFieldStock after = stock_after(stock, rest);
    // Bounded from the measure before (cheap), measured again only where a
    // bound is over.
    PassDepth now = pass_depth_bound(after, depth, p.cutter, p.leave, s.finish_max_depth);
    if (now.deepest > s.finish_max_depth + 1e-9) now = finishing_depth(after);
    grid_step = rest.grid.dx / 2;
    s.rest.push_back(std::move(rest));
    stock = std::move(after);
    depth = std::move(now);
    if (depth.deepest <= s.finish_max_depth + 1e-9) break;
    if (attempt == 3)
      throw std::invalid_argument(fmt::format(
          "after roughing and rest roughing with the {} the finishing pass would still cut {} at {}, more than its "
          "{}: give a smaller --leave or --step-down, or a smaller finishing cutter",
          p.cutter.spec(), mm(depth.deepest), where(depth), mm(s.finish_max_depth)));
    rr.near = depth.over;
  }
  s.rest_leave = rr.leave;
  s.rest_step_down = rr.step_down;
  s.finish_depth = depth.deepest;
  std::size_t levels = 0;
  for (const auto& r : s.rest) levels += r.levels.size();
  s.notes.push_back(fmt::format(
      "after roughing the finishing pass would still cut {} (at {}, where the {} grown by the leave does not fit), "
      "more than its cutter's {}: rest roughing with the {} near {} points of its moves too deep ({} levels{}), "
      "step-down at most {}, "
      "leaving {}; then the finishing cuts at most {}",
      mm(after_rough.deepest), where(after_rough), rc.spec(), mm(s.finish_max_depth), p.cutter.spec(), s.rest_spots,
      levels, s.rest.size() > 1 ? fmt::format(" in {} rounds, the later on finer grids", s.rest.size()) : "",
      mm(s.rest_step_down), mm(s.rest_leave), mm(s.finish_depth)));
  return s;
}

OperationSummary finishing_summary(const ToolpathProgram& r, const ToolpathParams& p, const ProgramStats& stats) {
  OperationSummary o;
  o.name = "finishing";
  o.cutter = r.cutter;
  o.detail = fmt::format("raster, {} rows {} mm apart along {}", r.path.rows.size(), row_spacing_text(r.path),
                         p.direction == RasterDirection::Y ? "Y" : "X");
  if (r.waterline_pieces > 0)
    o.detail = fmt::format("waterlines where steeper than {} degrees ({} levels {} mm apart, {} pieces), then {} with "
                           "{} steep stretches left to them",
                           format_gcode_number(p.steep_angle, 1), r.waterline_levels,
                           format_gcode_number(r.waterline_step, 4), r.waterline_pieces, o.detail, r.steep_bridges);
  o.lines = stats.lines;
  o.cut_length = stats.cut_length;
  o.feed_time_s = stats.feed_time_s;
  return o;
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
  auto begin = [&](const std::string& name, int tool, const Cutter& c) {
    auto at = std::make_pair(program.writer().lines().size(), program.stats());
    program.begin_operation({name, tool, c, p.rpm});
    return at;
  };
  auto summary = [&](OperationSummary o, const std::pair<std::size_t, ProgramStats>& at) {
    o.first_line = at.first + 1;
    o.lines = program.writer().lines().size() - at.first;
    o.cut_length = program.stats().cut_length - at.second.cut_length;
    o.feed_time_s = program.stats().feed_time_s - at.second.feed_time_s;
    r.operations.push_back(std::move(o));
  };

  int tool = 1;
  if (rough.path) {
    const auto at = begin("roughing", tool, rough.path->cutter);
    MachiningParams rm = mp;
    rm.feed = p.rough_feed.value_or(p.feed);
    write_roughing(program.writer(), *rough.path, r.work_offset, rm, program.stats());
    OperationSummary o;
    o.name = "roughing";
    o.tool = tool;
    o.cutter = rough.path->cutter;
    o.detail = fmt::format("Z-level, {} levels, stepover {} mm, leave {} mm", rough.path->levels.size(),
                           format_gcode_number(rough.path->stepover, 3), format_gcode_number(p.leave, 3));
    o.max_depth = rough.rough_max_depth;
    summary(std::move(o), at);
    // The same cutter finishes without a tool change.
    if (rough.path->cutter.spec() != p.cutter.spec()) ++tool;
  }
  if (!rough.rest.empty()) {
    // With the finishing cutter: the finishing follows without a tool change.
    const auto at = begin("rest roughing", tool, p.cutter);
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
    summary(std::move(o), at);
  }
  const auto at = begin("finishing", tool, p.cutter);
  write_pieces(program.writer(), r.finish_pieces, r.work_offset, mp, program.stats());
  OperationSummary f = finishing_summary(r, p, ProgramStats{});
  f.tool = tool;
  f.max_depth = rough.finish_depth;
  summary(std::move(f), at);
  if (rest && !rest->pieces.empty()) {
    ++tool;
    const auto at_rest = begin("rest machining", tool, rest->cutter);
    OperationSummary o;
    o.name = "rest machining";
    o.tool = tool;
    o.cutter = rest->cutter;
    std::size_t levels = 0;
    for (const auto& l : rest->levels) {
      write_roughing(program.writer(), l, r.work_offset, mp, program.stats());
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
    write_pieces(program.writer(), rest->pieces, r.work_offset, mp, program.stats());
    o.max_depth = rest->depth;
    summary(std::move(o), at_rest);
  }
  r.gcode = program.finish();
  r.stats = program.stats();
}

}  // namespace cncstream::jobs
