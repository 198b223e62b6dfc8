// Z-level roughing: levels, regions, and the passes that clear them.
#include "cncstream/cam/zlevel_roughing.hpp"

#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

#include "zlevel_regions.hpp"
#include "zlevel_stock.hpp"

namespace cncstream::cam {

namespace {

constexpr double kPi = 3.14159265358979323846;

std::string num(double v) {
  char buf[32];
  (void)std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

void check(const Cutter& cutter, const ClEngine& grown, const StockBlock& s, const RoughingParams& p) {
  auto positive = [](double v, const char* what) {
    if (!(v > 0) || !std::isfinite(v))
      throw std::invalid_argument(std::string("roughing: ") + what + " must be a positive length, got " + num(v));
  };
  positive(cutter.radius, "the cutter radius");
  positive(p.step_down, "the step down");
  positive(p.tolerance, "the tolerance");
  positive(p.clearance, "the clearance");
  if (!(p.stepover >= 0) || !std::isfinite(p.stepover)) throw std::invalid_argument("roughing: bad stepover " + num(p.stepover));
  if (!(p.grid_step >= 0) || !std::isfinite(p.grid_step))
    throw std::invalid_argument("roughing: bad grid step " + num(p.grid_step));
  if (!(p.ramp_angle_deg > 0 && p.ramp_angle_deg <= 45))
    throw std::invalid_argument("roughing: the ramp angle must be in (0, 45] degrees, got " + num(p.ramp_angle_deg));
  if (!(s.x1 > s.x0) || !(s.y1 > s.y0) || !std::isfinite(s.x0 + s.x1 + s.y0 + s.y1 + s.top))
    throw std::invalid_argument("roughing: the stock block has no area or is not finite");
  const Cutter want = grown_cutter(cutter, p.leave);  // checks leave
  const Cutter& got = grown.cutter();
  if (std::fabs(got.radius - want.radius) > 1e-9 || std::fabs(got.corner_radius - want.corner_radius) > 1e-9)
    throw std::invalid_argument("roughing: the CL engine's cutter " + got.spec() + " is not " + cutter.spec() +
                                " grown by the stock to leave (" + want.spec() + ")");
}

// The loop rotated to start at its vertex nearest to `from`.
Polyline rotated_near(const Polyline& loop, const geometry::Vec3& from) {
  std::size_t best = 0;
  double d = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < loop.size(); ++k)
    if (const double e = xy_dist(loop[k], from); e < d) d = e, best = k;
  Polyline out(loop.begin() + static_cast<long>(best), loop.end());
  out.insert(out.end(), loop.begin(), loop.begin() + static_cast<long>(best));
  return out;
}

struct Builder {
  Builder(const ClEngine& e, const RoughingParams& params, const StockBlock& s, RoughingPath& out)
      : grown(e), p(params), stock(s), path(out) {}
  const ClEngine& grown;
  const RoughingParams& p;
  const StockBlock& stock;
  RoughingPath& path;
  double R = 0, h = 0, leave = 0;
  double sx0 = 0, sy0 = 0, sx1 = 0, sy1 = 0;  // the stock's XY box
  double top = 0;                             // the stock's highest point
  double scallop = 0;                         // left between loops above a level
  double clearance_z = 0;
  // A rest roughing's window per node (<= 0: inside); empty: everywhere.
  std::vector<double> window;

  // Signed distance from the stock's XY box grown by the radius (rounded
  // corners: beyond them the cutter meets no stock).
  double dbox(double x, double y) const {
    const double ex = std::max(sx0 - x, x - sx1), ey = std::max(sy0 - y, y - sy1);
    const double out = std::hypot(std::max(ex, 0.0), std::max(ey, 0.0));
    return (out > 0 ? out : std::max(ex, ey)) - R;
  }
  // <= 0 where the tip may go down to z (and, given `reach`, is within
  // reach of material above z). Safe to call concurrently.
  double region_value(double x, double y, double z, const std::vector<double>* reach = nullptr) const {
    double v = dbox(x, y);
    if (!window.empty()) v = std::max(v, detail::interpolate(path.grid, window, x, y));
    if (reach) v = std::max(v, detail::interpolate(path.grid, *reach, x, y));
    if (v > 0) return v;
    return std::max(grown.height_at(x, y) + leave - z, v);
  }
  double phi(double x, double y, double z) {
    ++path.stats.point_queries;
    return region_value(x, y, z);
  }
  // Whether the straight move a-b (both ends on loops) lies in the tip
  // region of level z (exact queries) and in what the loops of the level
  // above cleared (`cleared`, its boundary loops; empty: all, the stock's
  // top): away from the ends in cells whose corners are all inside as the
  // grid saw it (`mask`, of loops inside `cleared`), near the ends inside
  // `cleared` itself - not in a sliver of the region too thin for the grid,
  // which no loop visited.
  bool segment_inside(const geometry::Vec3& a, const geometry::Vec3& b, double z, const std::vector<std::uint8_t>& mask,
                      const std::vector<Polyline>* cleared) {
    const GridSpec& g = path.grid;
    const double len = xy_dist(a, b);
    const auto n = static_cast<std::size_t>(std::ceil(len / (h / 2)));
    for (std::size_t k = 0; k <= n; ++k) {
      const double t = n ? static_cast<double>(k) / static_cast<double>(n) : 0.0;
      const double x = a.x + (b.x - a.x) * t, y = a.y + (b.y - a.y) * t;
      if (phi(x, y, z) > 0) return false;
      if (std::min(t, 1 - t) * len <= 1.5 * h) {
        if (cleared && k > 0 && k < n && !detail::inside_loops({x, y, z}, *cleared)) return false;
        continue;
      }
      const auto i = static_cast<std::size_t>(std::floor((x - g.x0) / g.dx));
      const auto j = static_cast<std::size_t>(std::floor((y - g.y0) / g.dy));
      if (i + 1 >= g.nx || j + 1 >= g.ny) return false;
      const std::size_t c = j * g.nx + i;
      if (!mask[c] || !mask[c + 1] || !mask[c + g.nx] || !mask[c + g.nx + 1]) return false;
    }
    return true;
  }
  std::vector<std::uint8_t> mask, mask_above;  // nodes inside the region: this level, the level above
  std::vector<Polyline> boundary_above;  // the boundary loops of the level above

  bool k_first_level(double z_above) const { return z_above >= top; }  // above: the stock itself

  // A new pass from `from` (if any) to the loop, lifted, ramping down along
  // the loop from just above z_above to z, then the loop at z.
  RoughingPass entry(const std::optional<geometry::Vec3>& from, const Polyline& loop, double length, double z, double z_above) {
    RoughingPass pass;
    pass.lift_before = true;
    pass.lift_z = clearance_z;
    // Over a cleared level: above its scallops.
    const double above = k_first_level(z_above) ? 0.0 : scallop;
    const double low = std::min(z_above + above + std::min(p.clearance, 1.0), clearance_z);
    // Over the level above's loops, or over the stock's top.
    const bool over_top = k_first_level(z_above);
    const std::vector<Polyline>* cleared = &boundary_above;
    if (from && low < clearance_z &&
        (over_top || segment_inside(*from, loop.front(), z_above, mask_above, cleared))) {
      pass.lift_z = low;
      ++path.stats.low_lifts;
    } else {
      ++path.stats.high_lifts;
    }
    const double ramp_top = std::min(z_above + above + 0.5, pass.lift_z);
    const double drop = ramp_top - z;
    // A loop shorter than the cutter's radius is a spot the tool covers
    // anyway: laps of it would be a zigzag of hundredths of a millimetre
    // (a line each, more than a serial link can deliver), so it plunges.
    const double need = length < R ? 0.0 : drop / std::tan(p.ramp_angle_deg * kPi / 180);
    if (length < (p.min_ramp_loop > 0 ? p.min_ramp_loop : kPi * R / 2)) ++path.stats.short_entries;
    // Down along the loop over the length the angle needs (laps of a short
    // loop), not a whole lap of a long one at the plunge feed; then one
    // whole lap at z from where the ramp got down.
    pass.points.push_back({loop.front().x, loop.front().y, ramp_top});
    const std::size_t n = loop.size();
    // The ramp runs along chords of the loop that stay inside the level's
    // region (material to be removed, above the part): the loop's own
    // vertices are a few tenths apart round small pockets, a line each at
    // the plunge feed, more than a serial link delivers.
    auto chord_end = [&](std::size_t from) {
      std::size_t to = from + 1;
      // Short of a whole lap: loop[from + n] is loop[from] again.
      for (std::size_t m = from + 2; m < from + std::min<std::size_t>(n, 64); ++m) {
        if (xy_dist(loop[from % n], loop[m % n]) > 4 * R) break;
        if (!segment_inside(loop[from % n], loop[m % n], z, mask, nullptr)) break;
        to = m;
      }
      return to;
    };
    double s = 0;
    std::size_t k = 0;
    geometry::Vec3 down = loop.front();
    bool back_to_down = true;  // the lap closes at `down` (else at its chord's end)
    for (;;) {
      const std::size_t next = n > 2 && need > 0 ? chord_end(k) : k + 1;
      const geometry::Vec3& a = loop[k % n];
      const geometry::Vec3& b = loop[next % n];
      const double seg = xy_dist(a, b);
      if (s + seg >= need || (k + 1 >= n && s + seg <= 1e-9)) {
        const double t = seg > 0 ? std::clamp((need - s) / seg, 0.0, 1.0) : 1.0;
        down = t >= 1 ? geometry::Vec3{b.x, b.y, z} : geometry::Vec3{a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t, z};
        pass.points.push_back(down);
        if (t < 1 && next > k + 1) {
          // Down inside a chord: on along it to its end, where the lap starts.
          pass.points.push_back({b.x, b.y, z});
          back_to_down = false;
        }
        if (t >= 1 || next > k + 1) k = next;  // the lap starts at b
        break;
      }
      s += seg;
      pass.points.push_back({b.x, b.y, ramp_top - drop * s / need});
      k = next;
    }
    pass.entry_points = pass.points.size() - 1 - (back_to_down ? 0 : 1);
    // The lap: the vertices after `down` (or its chord's end) round to it.
    for (std::size_t m = 1; m <= n; ++m) {
      const geometry::Vec3& v = loop[(k + m) % n];
      pass.points.push_back({v.x, v.y, z});
    }
    if (back_to_down && (pass.points.back().x != down.x || pass.points.back().y != down.y)) pass.points.push_back(down);
    return pass;
  }

  static void append_loop(Polyline& out, const Polyline& loop, double z, bool with_start) {
    for (std::size_t k = with_start ? 0 : 1; k <= loop.size(); ++k) {
      const geometry::Vec3& v = loop[k % loop.size()];
      out.push_back({v.x, v.y, z});
    }
  }

  void level(const detail::LevelRegion& region, double z, double z_above, RoughingLevel& out,
             std::optional<geometry::Vec3>& at) {
    // Loops per component, in cutting order.
    std::vector<std::vector<const detail::RegionLoop*>> parts(region.components);
    for (const auto& l : region.loops) parts[l.component].push_back(&l);
    std::vector<std::uint8_t> done(parts.size(), 0);
    const bool inside_out = p.order == ClearingOrder::InsideOut;
    for (std::size_t round = 0; round < parts.size(); ++round) {
      // The nearest component not yet cut.
      std::size_t pick = parts.size();
      double best = std::numeric_limits<double>::infinity();
      for (std::size_t c = 0; c < parts.size(); ++c) {
        if (done[c] || parts[c].empty()) continue;
        const double d = at ? xy_dist(*at, parts[c].front()->points.front()) : 0.0;
        if (d < best) best = d, pick = c;
      }
      if (pick == parts.size()) break;
      done[pick] = 1;
      auto loops = parts[pick];
      // Offsets inside out (boundary last) or outside in (boundary last).
      auto rank = [&](int offset) { return offset == 0 ? -1 : (inside_out ? offset : 1000000 - offset); };
      std::stable_sort(loops.begin(), loops.end(),
                       [&](const auto* a, const auto* b) { return rank(a->offset) > rank(b->offset); });
      // Nearest neighbour within each offset.
      geometry::Vec3 cursor = at ? *at : loops.front()->points.front();
      for (std::size_t k = 0; k < loops.size(); ++k) {
        std::size_t best_k = k;
        double bd = std::numeric_limits<double>::infinity();
        for (std::size_t m = k; m < loops.size() && loops[m]->offset == loops[k]->offset; ++m)
          for (const geometry::Vec3& v : loops[m]->points)
            if (const double d = xy_dist(v, cursor); d < bd) bd = d, best_k = m;
        std::swap(loops[k], loops[best_k]);
        cursor = rotated_near(loops[k]->points, cursor).front();
      }
      // Ramp in along the first loop long enough to ramp on.
      const double min_loop = p.min_ramp_loop > 0 ? p.min_ramp_loop : kPi * R / 2;
      auto first = std::find_if(loops.begin(), loops.end(), [&](const auto* l) { return l->length >= min_loop; });
      if (first == loops.end())
        first = std::max_element(loops.begin(), loops.end(), [](const auto* a, const auto* b) { return a->length < b->length; });
      std::rotate(loops.begin(), first, first + 1);

      for (const auto* l : loops) {
        ++path.stats.loops;
        const bool material_outside = inside_out || l->offset == 0;
        Polyline pts = l->points;
        if (material_outside != p.climb) std::reverse(pts.begin(), pts.end());
        if (at) pts = rotated_near(pts, *at);
        for (auto& v : pts) v.z = z;
        const bool first_of_part = l == loops.front();
        const std::vector<Polyline>* cleared = k_first_level(z_above) ? nullptr : &boundary_above;
        if (!first_of_part && at && segment_inside(*at, pts.front(), z, mask, cleared)) {
          append_loop(out.passes.back().points, pts, z, true);
        } else {
          out.passes.push_back(entry(at, pts, l->length, z, z_above));
        }
        at = out.passes.back().points.back();
      }
    }
  }
};

}  // namespace

RoughingPath build_zlevel_roughing(const ClEngine& grown, const Cutter& cutter, const StockBlock& stock,
                                   const RoughingParams& p, const Checkpoint& checkpoint) {
  check(cutter, grown, stock, p);
  if (!p.near.empty() && !(p.near_radius > 0 && std::isfinite(p.near_radius)))
    throw std::invalid_argument("roughing: the radius around the points to clear near must be positive, got " +
                                num(p.near_radius));
  RoughingPath path;
  path.cutter = cutter;
  path.leave = p.leave;
  Builder b(grown, p, stock, path);
  b.R = cutter.radius;
  b.leave = p.leave;
  // Cells small enough that a chord across one leaves the region (curved at
  // a radius of at least R where it is concave) by at most tolerance / 2.
  b.h = p.grid_step > 0 ? p.grid_step : std::min(b.R / 6, std::sqrt(2 * p.tolerance * b.R));
  // Loops closer than the radius (less the half cell the distance transform
  // may be off by, twice) overlap, so no material is left between them.
  const double s_max = b.R - b.h;
  if (!(s_max > 0)) throw std::invalid_argument("roughing: grid step " + num(b.h) + " is not below the cutter radius");
  path.stepover = std::min(p.stepover > 0 ? p.stepover : 0.8 * b.R, s_max);
  b.sx0 = stock.x0, b.sy0 = stock.y0, b.sx1 = stock.x1, b.sy1 = stock.y1;
  const double margin = b.R + 1.5 * b.h;
  double gx0 = stock.x0 - margin, gy0 = stock.y0 - margin, gx1 = stock.x1 + margin, gy1 = stock.y1 + margin;
  if (!p.near.empty()) {
    // Only what reaches the window: a tip in it, its cutter, and the
    // material under the cutter (the clearance height is above all of it).
    double nx0 = HUGE_VAL, ny0 = HUGE_VAL, nx1 = -HUGE_VAL, ny1 = -HUGE_VAL;
    for (const geometry::Vec3& v : p.near) {
      if (!std::isfinite(v.x) || !std::isfinite(v.y)) throw std::invalid_argument("roughing: a point to clear near is not finite");
      nx0 = std::min(nx0, v.x), ny0 = std::min(ny0, v.y), nx1 = std::max(nx1, v.x), ny1 = std::max(ny1, v.y);
    }
    const double w = p.near_radius + b.h + margin;
    gx0 = std::max(gx0, nx0 - w), gy0 = std::max(gy0, ny0 - w);
    gx1 = std::min(gx1, nx1 + w), gy1 = std::min(gy1, ny1 + w);
    if (!(gx0 + 2 * b.h < gx1 && gy0 + 2 * b.h < gy1)) return path;  // nothing of the stock near them
  }
  path.grid = GridSpec::covering(gx0, gy0, gx1, gy1, b.h, b.h);
  const GridSpec& g = path.grid;
  if (!p.near.empty()) {
    // The corners of each point's cell, and the window a cell wider than
    // asked (a point is within a cell diagonal of its nearest corner).
    std::vector<double> seed(g.size(), 0.0);
    for (const geometry::Vec3& v : p.near) {
      const double fx = (v.x - g.x0) / g.dx, fy = (v.y - g.y0) / g.dy;
      if (fx < 0 || fy < 0 || fx > static_cast<double>(g.nx - 1) || fy > static_cast<double>(g.ny - 1)) continue;
      const auto i = std::min(static_cast<std::size_t>(fx), g.nx - 2), j = std::min(static_cast<std::size_t>(fy), g.ny - 2);
      for (std::size_t dj = 0; dj < 2; ++dj)
        for (std::size_t di = 0; di < 2; ++di) seed[(j + dj) * g.nx + i + di] = 1.0;
    }
    b.window = detail::material_reach(g, seed, 0.5, 0.0, p.near_radius + b.h);
  }
  const ClGrid cl = grown.compute(g);
  if (checkpoint) checkpoint(0.1);
  // A machined stock: its top on the grid, and levels from its highest point.
  std::vector<double> stock_top;
  b.top = stock.top;
  if (stock.surface) {
    stock_top = detail::stock_top_on_grid(g, stock);
    b.top = -std::numeric_limits<double>::infinity();
    for (double t : stock_top) b.top = std::max(b.top, t);
  }
  b.clearance_z = path.clearance_z = b.top + p.clearance;

  std::vector<double> tips(g.size()), in_box, flat;
  for (std::size_t n = 0; n < g.size(); ++n) tips[n] = cl.z[n] + p.leave;
  // Flat: the four neighbours level with the node within the flat tolerance.
  const double flat_tol = p.tolerance / 5;
  for (std::size_t j = 1; j + 1 < g.ny; ++j)
    for (std::size_t i = 1; i + 1 < g.nx; ++i) {
      const std::size_t n = j * g.nx + i;
      if (b.dbox(g.x(i), g.y(j)) > 0) continue;
      if (!b.window.empty() && b.window[j * g.nx + i] > 0) continue;  // levels for the window only
      in_box.push_back(tips[n]);
      const double t = tips[n];
      if (std::fabs(tips[n - 1] - t) <= flat_tol && std::fabs(tips[n + 1] - t) <= flat_tol &&
          std::fabs(tips[n - g.nx] - t) <= flat_tol && std::fabs(tips[n + g.nx] - t) <= flat_tol)
        flat.push_back(t);
    }
  const double min_flat = p.flat_min_area > 0 ? p.flat_min_area : kPi * b.R * b.R / 4;
  // A round cutter leaves scallops between its loops, up to its profile at
  // the farthest a point is from a loop (a stepover and a cell); the next
  // level cuts them too, so the levels are that much closer than the step
  // down and no move cuts deeper.
  const double scallop = b.scallop = cutter.profile_height(std::min(cutter.radius, path.stepover + b.h));
  RoughingParams spaced = p;
  spaced.step_down = p.step_down - scallop;
  if (!(spaced.step_down > 0.1 * p.step_down))
    throw std::invalid_argument("roughing: the scallop between loops of " + cutter.spec() + " at stepover " +
                                num(path.stepover) + " (" + num(scallop) + " mm) leaves no room in the step down " +
                                num(p.step_down) + "; use a smaller stepover");
  LevelPlan plan = plan_levels(in_box, flat, b.h * b.h, b.top, spaced, min_flat);
  if (!p.near.empty()) {
    // A level between where the tip can go at each point and its z plus
    // the step down and leave, less the scallop (so the stock there comes
    // within that of z: in a gap the cutter grown by the leave does not fit
    // its tip stops above the part, and the levels' spacing alone may leave
    // a level up to a step above that). Fewest levels: by the top of each
    // interval, one at the top of each not yet met.
    std::vector<std::pair<double, double>> want;  // (hi, lo)
    for (const geometry::Vec3& v : p.near) {
      const double lo = grown.height_at(v.x, v.y) + p.leave;
      double hi = std::min(v.z + p.step_down + p.leave - scallop, b.top);
      if (p.bottom && hi < *p.bottom) continue;
      if (lo < hi - 1e-9) want.emplace_back(hi, lo);
    }
    std::sort(want.begin(), want.end());
    std::vector<double> added;
    for (const auto& [hi, lo] : want) {
      auto met = [&, lo = lo, hi = hi](double z) { return z >= lo && z <= hi; };
      if (std::any_of(plan.z.begin(), plan.z.end(), met) || std::any_of(added.begin(), added.end(), met)) continue;
      added.push_back(hi);
    }
    for (double z : added) plan.z.push_back(z), plan.flat.push_back(false);
    std::vector<std::size_t> order(plan.z.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t c) { return plan.z[a] > plan.z[c]; });
    LevelPlan sorted;
    for (std::size_t k : order) sorted.z.push_back(plan.z[k]), sorted.flat.push_back(plan.flat[k]);
    plan = std::move(sorted);
  }

  // Material left: the largest gap between levels and the scallop.
  double gap = 0;
  for (std::size_t k = 0; k < plan.z.size(); ++k) gap = std::max(gap, (k ? plan.z[k - 1] : b.top) - plan.z[k]);
  path.terrace_bound = gap + scallop;

  // The regions of all levels at once (independent), then the passes in order.
  std::vector<detail::LevelRegion> regions(plan.z.size());
  std::atomic<std::size_t> regions_done{0};
  tbb::parallel_for(std::size_t{0}, plan.z.size(), [&](std::size_t k) {
    const double z = plan.z[k];
    std::vector<double> phi(g.size()), reach;
    // Within reach of material above z: the radius and two cells (the
    // stock's top on the grid is the highest within a cell of each node, and
    // the distance is between nodes), so a tip left out has no material
    // above z under the cutter.
    // Material counts where it stands more than the flat tolerance above z
    // (a level cut before stands up to the G-code's rounding of Z above it).
    if (stock.surface) reach = detail::material_reach(g, stock_top, z, flat_tol, b.R + 2 * b.h);
    for (std::size_t n = 0; n < g.size(); ++n) {
      phi[n] = std::max(tips[n] - z, b.dbox(g.x(n % g.nx), g.y(n / g.nx)));
      if (!b.window.empty()) phi[n] = std::max(phi[n], b.window[n]);
      if (stock.surface) phi[n] = std::max(phi[n], reach[n]);
    }
    const std::vector<double>* within = stock.surface ? &reach : nullptr;
    const PointQuery exact = [&b, z, within](double x, double y) { return b.region_value(x, y, z, within); };
    detail::RegionInput in;
    in.grid = &g;
    in.phi = &phi;
    in.exact = &exact;
    in.stepover = path.stepover;
    in.boundary_tolerance = p.tolerance / 4;
    in.inner_tolerance = b.h / 4;
    regions[k] = detail::level_region(in);
    if (checkpoint) checkpoint(0.1 + 0.8 * static_cast<double>(++regions_done) / static_cast<double>(plan.z.size()));
  });
  std::optional<geometry::Vec3> at;
  for (std::size_t k = 0; k < plan.z.size(); ++k) {
    const double z = plan.z[k], z_above = k ? plan.z[k - 1] : b.top;
    path.stats.point_queries += regions[k].queries;
    path.stats.corners_dropped += detail::settle_boundary(regions[k], k > 0 ? &b.boundary_above : nullptr);
    b.mask_above.swap(b.mask);
    b.mask = std::move(regions[k].inside);
    RoughingLevel lv;
    lv.z = z;
    lv.flat = plan.flat[k];
    b.level(regions[k], z, z_above, lv, at);
    b.boundary_above.clear();
    for (const auto& l : regions[k].loops)
      if (l.offset == 0) b.boundary_above.push_back(l.points);
    if (!lv.passes.empty()) path.levels.push_back(std::move(lv));
  }
  if (checkpoint) checkpoint(1.0);
  for (const auto& lv : path.levels) {
    path.stats.passes += lv.passes.size();
    for (std::size_t q = 0; q < lv.passes.size(); ++q) {
      const Polyline& pts = lv.passes[q].points;
      if (q > 0 && !lv.passes[q].lift_before) path.stats.cut_length += norm(pts.front() - lv.passes[q - 1].points.back());
      for (std::size_t k = 1; k < pts.size(); ++k) path.stats.cut_length += norm(pts[k] - pts[k - 1]);
    }
  }
  return path;
}

}  // namespace cncstream::cam
