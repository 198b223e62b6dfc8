#include "roughing_stage.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/path_machining.hpp"
#include "cncstream/cam/pass_depth.hpp"

namespace cncstream::jobs {

namespace {

// The deepest the pass cuts below the stock's top: over its points whose
// cutter reaches over the stock (work coordinates).
double depth_below_stock(const std::vector<cam::Polyline>& pieces, const geometry::Vec3& offset, const WorkStock& stock,
                         double radius) {
  double deepest = 0;
  auto visit = [&](const cam::Polyline& pl) {
    for (const geometry::Vec3& m : pl) {
      const geometry::Vec3 v = m + offset;
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
cam::HeightFieldStock model_surface(const cam::HeightFieldData& map, const geometry::Vec3& work_offset, double top) {
  cam::GridSpec g = map.grid;
  g.x0 -= work_offset.x;
  g.y0 -= work_offset.y;
  std::vector<double> z(map.z.size());
  for (std::size_t n = 0; n < z.size(); ++n)
    z[n] = std::isfinite(map.z[n]) ? static_cast<double>(map.z[n]) - work_offset.z : top;
  return cam::HeightFieldStock(g, top, std::move(z));
}

std::string mm(double v) { return fmt::format("{:.2f} mm", v); }

// The stock before the roughing on a grid over the block (model
// coordinates): the block's top, or the height map's surface below it.
cam::HeightFieldStock stock_before(const cam::StockBlock& block, double cell) {
  const cam::GridSpec g = cam::GridSpec::covering(block.x0, block.y0, block.x1, block.y1, cell, cell);
  std::vector<double> z(g.size(), block.top);
  if (block.surface)
    for (std::size_t j = 0; j < g.ny; ++j)
      for (std::size_t i = 0; i < g.nx; ++i)
        if (const double h = cam::stock_height_at(*block.surface, g.x(i), g.y(j)); std::isfinite(h))
          z[j * g.nx + i] = std::min(h, block.top);
  return cam::HeightFieldStock(g, block.top, std::move(z));
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

double round_stepover(const cam::Cutter& c, double step_down) {
  if (!c.is_apt()) {
    // A tapered ball or V-bit: from its tip, not its top (the cone rises
    // steeply beyond the tip): half the radius at which the profile rises a
    // quarter of the step down.
    const double t = std::min(c.profile_top(), step_down / 4);
    double lo = 0, hi = c.radius;
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (lo + hi);
      (c.profile_height(mid) < t ? lo : hi) = mid;
    }
    return std::max(0.02, 0.5 * lo);
  }
  const double t = std::min(c.corner_radius, step_down / 4);
  const double reach =
      c.core_radius() + std::sqrt(c.corner_radius * c.corner_radius - (c.corner_radius - t) * (c.corner_radius - t));
  return std::clamp(reach - c.radius / 6, 0.1 * c.diameter(), 0.4 * c.diameter());
}

cam::HeightFieldStock stock_after(const cam::HeightFieldStock& stock, const cam::RoughingPath& path) {
  std::vector<double> z = cam::machine_path(stock.grid(), stock.heights(), {cam::roughing_moves(path)}, path.cutter);
  return cam::HeightFieldStock(stock.grid(), stock.top(), std::move(z));
}

namespace {

// The stock as a block in model coordinates; a height map its surface
// (levels start below its highest point and cut only where there is
// material above them).
cam::StockBlock model_block(const RoughingStage& s, const geometry::Vec3& work_offset) {
  cam::StockBlock block;
  block.x0 = s.stock.box.lo.x - work_offset.x;
  block.y0 = s.stock.box.lo.y - work_offset.y;
  block.x1 = s.stock.box.hi.x - work_offset.x;
  block.y1 = s.stock.box.hi.y - work_offset.y;
  block.top = s.stock.box.hi.z - work_offset.z;
  block.surface = s.surface.get();
  return block;
}

// No level below the stock's bottom (an open mesh would let the tip go
// below the part's floor).
double block_bottom(const RoughingStage& s, const geometry::Vec3& work_offset) { return s.stock.box.lo.z - work_offset.z; }

// The Z-level roughing from the stock into s.path (its summary in
// s.path_note).
void add_roughing_path(RoughingStage& s, const ToolpathParams& p, const geometry::Mesh& mesh, const geometry::Vec3& work_offset,
                       const cam::Checkpoint& checkpoint) {
  const cam::Cutter rc = s.rough_cutter;
  s.rough_max_depth = p.rough_max_depth.value_or(default_max_depth(rc));
  if (!(s.rough_max_depth > 0)) throw std::invalid_argument("the roughing cutter's maximum depth must be positive");
  if (!(p.leave >= 0)) throw std::invalid_argument("the stock to leave must not be negative");
  if (!(p.leave < s.finish_max_depth))
    throw std::invalid_argument(fmt::format("the stock to leave ({}) is not less than the finishing cutter's maximum depth "
                                            "({}): the finishing pass could not take it",
                                            mm(p.leave), mm(s.finish_max_depth)));
  const cam::StockBlock block = model_block(s, work_offset);
  cam::RoughingParams rp;
  rp.leave = p.leave;
  rp.bottom = block_bottom(s, work_offset);
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
  cam::ClOptions clo;
  clo.floor = p.floor;
  const cam::ClEngine grown(mesh, cam::grown_cutter(rc, p.leave), clo);
  cam::RoughingPath path = cam::build_zlevel_roughing(grown, rc, block, rp, checkpoint);
  // The terraces' bound came out above what the finishing cutter may take
  // (round cutters leave scallops between loops too): once more with the
  // levels closer by the excess.
  double after = p.leave + path.terrace_bound;
  if (after > s.finish_max_depth + 1e-9 && !p.step_down) {
    rp.step_down -= after - s.finish_max_depth;
    if (rp.step_down > 0.05) {
      path = cam::build_zlevel_roughing(grown, rc, block, rp, checkpoint);
      after = p.leave + path.terrace_bound;
    }
  }
  s.path_note = fmt::format("roughing: {} levels, step-down at most {}, stepover {}, leaving {} (terraces up to {} more)",
                                path.levels.size(), mm(rp.step_down), mm(path.stepover), mm(p.leave),
                                mm(path.terrace_bound));
  s.path = std::move(path);
  // The stock it leaves, on a grid fine enough for the finishing cutter
  // (check_roughing measures the finishing pass's depth of cut against it).
  const double cell = std::min(0.25, p.cutter.radius / 4);
  s.roughed = std::make_shared<const cam::HeightFieldStock>(stock_after(stock_before(block, cell), *s.path));
}

}  // namespace

RoughingStage roughing_from_stock(const ToolpathParams& p, const geometry::Mesh& mesh, const geometry::Vec3& work_offset,
                                  bool with_path, const cam::Checkpoint& checkpoint) {
  RoughingStage s;
  geometry::Box3 part = mesh.bounds();
  part.lo = part.lo + work_offset;
  part.hi = part.hi + work_offset;
  s.stock = resolve_stock(*p.stock, part);
  s.finish_max_depth = p.max_depth.value_or(default_max_depth(p.cutter));
  if (!(s.finish_max_depth > 0)) throw std::invalid_argument("the maximum depth of cut must be positive");
  s.rough_cutter = p.rough.value_or(p.cutter);
  if (s.stock.heights)
    s.surface = std::make_shared<const cam::HeightFieldStock>(
        model_surface(*s.stock.heights, work_offset, s.stock.box.hi.z - work_offset.z));
  if (with_path) add_roughing_path(s, p, mesh, work_offset, checkpoint);
  return s;
}

void check_roughing(RoughingStage& s, const ToolpathParams& p, const geometry::Mesh& mesh,
                    const std::vector<cam::Polyline>& finishing, const geometry::Vec3& work_offset, const cam::Checkpoint& checkpoint) {
  s.finish_depth_alone = depth_below_stock(finishing, work_offset, s.stock, p.cutter.radius);
  s.finish_depth = s.finish_depth_alone;
  const bool needed = s.finish_depth_alone > s.finish_max_depth + 1e-9;
  if (!needed && !p.rough) {
    s.notes.push_back(fmt::format("the finishing pass cuts at most {} below the stock's top, within its cutter's {}: "
                                  "no roughing",
                                  mm(s.finish_depth_alone), mm(s.finish_max_depth)));
    return;
  }
  if (needed)
    s.notes.push_back(fmt::format("the finishing pass alone would cut {} deep in one pass, more than the {}'s {}: "
                                  "roughing first with the {}",
                                  mm(s.finish_depth_alone), p.cutter.spec(), mm(s.finish_max_depth),
                                  s.rough_cutter.spec()));
  else
    s.notes.push_back(fmt::format("roughing with the {} as asked", s.rough_cutter.spec()));
  if (!s.path) add_roughing_path(s, p, mesh, work_offset, checkpoint);
  s.notes.push_back(s.path_note);

  // The finishing pass cut into the stock the roughing leaves (a height
  // map fine enough for the finishing cutter): where the roughing cutter
  // could not reach (gaps narrower than it grown by the leave), it would
  // still cut deep. Its depth of cut leaves out a rim as wide as the leave:
  // its side cut of the skin along a wall is as tall as the wall.
  const cam::StockBlock block = model_block(s, work_offset);
  const double retract_z = block.top + 1;
  auto finishing_depth = [&](const cam::HeightFieldStock& stock) {
    return cam::pass_depth(stock, finishing, p.cutter, p.leave, s.finish_max_depth, retract_z);
  };
  auto where = [&](const cam::PassDepth& e) {
    return fmt::format("X{:.3f} Y{:.3f} (work coordinates; down to Z{:.3f})", e.at.x + work_offset.x,
                       e.at.y + work_offset.y, e.at.z + work_offset.z);
  };
  const cam::HeightFieldStock& roughed = *s.roughed;
  const cam::PassDepth after_rough = finishing_depth(roughed);
  s.finish_depth = after_rough.deepest;
  if (after_rough.deepest <= s.finish_max_depth + 1e-9) {
    s.notes.push_back(fmt::format("after roughing the finishing pass cuts at most {}, within its cutter's {}",
                                  mm(after_rough.deepest), mm(s.finish_max_depth)));
    return;
  }

  // Rest roughing with the finishing cutter (no tool change before the
  // finishing) near where it would cut too deep, from the roughed stock:
  // levels only where material stands above them, each within the
  // finishing cutter's depth, and one that brings the stock there within it.
  s.rest_spots = after_rough.over.size();
  cam::RoughingParams rr;
  rr.tolerance = 0.05;
  rr.leave = std::min(p.leave, std::max(kRestLeave, rr.tolerance / 2 + p.tolerance));
  rr.bottom = block_bottom(s, work_offset);
  rr.near = after_rough.over;
  // The cutter over a spot from anywhere it can lower it (the window is a
  // grid cell wider).
  rr.near_radius = p.cutter.radius;
  rr.step_down = s.finish_max_depth - rr.leave;
  if (p.cutter.corner_radius > 0) rr.stepover = round_stepover(p.cutter, rr.step_down);
  cam::StockBlock rest_block = block;
  cam::ClOptions clo;
  clo.floor = p.floor;
  const cam::ClEngine grown_finish(mesh, cam::grown_cutter(p.cutter, rr.leave), clo);
  // The stage's progress stays where the roughing ended; a stop request
  // still stops it.
  cam::Checkpoint rest_checkpoint;
  if (checkpoint) rest_checkpoint = [&checkpoint](double) { checkpoint(1.0); };
  // What a rest roughing leaves too deep (its regions come from a grid: a
  // pit the finishing ball drops into, narrower than a cell, is missed) gets
  // another near it alone, from the stock after it, on a grid half as fine.
  cam::HeightFieldStock stock = roughed;
  cam::PassDepth depth = after_rough;
  double grid_step = 0;  // the roughing's default first
  for (int attempt = 1;; ++attempt) {
    rest_block.surface = &stock;
    rr.grid_step = grid_step;
    cam::RoughingPath rest = cam::build_zlevel_roughing(grown_finish, p.cutter, rest_block, rr, rest_checkpoint);
    if (rest.levels.empty())
      throw std::invalid_argument(fmt::format(
          "after roughing{} the finishing pass would still cut {} at {}, more than the {}'s {}, and a rest roughing "
          "with it finds nothing it can cut there: give a smaller --leave or --step-down",
          s.rest.empty() ? "" : " and rest roughing", mm(depth.deepest), where(depth), p.cutter.spec(),
          mm(s.finish_max_depth)));
    cam::HeightFieldStock after = stock_after(stock, rest);
    // Bounded from the measure before (cheap), measured again only where a
    // bound is over.
    cam::PassDepth now = cam::pass_depth_bound(after, depth, p.cutter, p.leave, s.finish_max_depth);
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
      mm(after_rough.deepest), where(after_rough), s.rough_cutter.spec(), mm(s.finish_max_depth), p.cutter.spec(), s.rest_spots,
      levels, s.rest.size() > 1 ? fmt::format(" in {} rounds, the later on finer grids", s.rest.size()) : "",
      mm(s.rest_step_down), mm(s.rest_leave), mm(s.finish_depth)));
}


}  // namespace cncstream::jobs
