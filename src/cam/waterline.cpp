#include "cncstream/cam/waterline.hpp"

#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "cncstream/cam/level_band_fit.hpp"
#include "cncstream/cam/level_contours.hpp"
#include "cncstream/cam/polyline_simplify.hpp"

namespace cncstream::cam {

namespace {


// The largest rise of the CL above a level run's chord that is moved out of
// sideways rather than lifted over (append_lifted).
constexpr double kSmallSag = 2e-3;

// How far the exact CL may stand above a fitted level move (the contour's
// own points are on the CL within a micron).
constexpr double kClearSlack = 2e-5;

// (x, y) on the lattice: the nearest lattice point where the CL allows the
// point's height, else the nearest one lifted onto the CL there.
geometry::Vec3 on_lattice(const ClEngine& engine, const std::optional<XYLattice>& lat, geometry::Vec3 p, std::size_t& queries) {
  if (!lat) return p;
  const double s = lat->step;
  const double i0 = std::round((p.x - lat->x0) / s), j0 = std::round((p.y - lat->y0) / s);
  struct Cand {
    double x, y, d;
  };
  std::vector<Cand> cands;
  // Two lattice steps around: a contour point is on the CL within a micron,
  // and where the CL rises gently a step beside it may not yet be below the
  // level; lifting it by that fraction of a micron would break the level.
  for (int di = -2; di <= 2; ++di)
    for (int dj = -2; dj <= 2; ++dj) {
      const double x = lat->x0 + (i0 + di) * s, y = lat->y0 + (j0 + dj) * s;
      cands.push_back({x, y, std::hypot(x - p.x, y - p.y)});
    }
  std::sort(cands.begin(), cands.end(), [](const Cand& a, const Cand& b) { return a.d < b.d; });
  for (const Cand& c : cands) {
    ++queries;
    const double cl = engine.height_at(c.x, c.y);
    if (cl <= p.z) return {c.x, c.y, p.z};
  }
  ++queries;
  return {cands.front().x, cands.front().y, std::max(p.z, engine.height_at(cands.front().x, cands.front().y))};
}

// How far (x, y) must move along (nx, ny), from `from` on, for the CL there
// to be at or below the level (out by doublings, then in to 1/4096 of the
// bracket); inf past `limit`. What it returns was queried at or below the
// level.
double free_offset(const ClEngine& engine, double x, double y, double nx, double ny, double level, double from,
                   double limit, std::size_t& queries) {
  auto above = [&](double t) {
    ++queries;
    return engine.height_at(x + t * nx, y + t * ny) - level;
  };
  double lo = from, hi = std::max(from, 1e-4);
  double f_lo = std::numeric_limits<double>::quiet_NaN(), f_hi = above(hi);
  while (f_hi > 0) {
    lo = hi;
    f_lo = f_hi;
    hi *= 2;
    if (hi > limit) return HUGE_VAL;
    f_hi = above(hi);
  }
  // Across a contour the CL is close to linear, so regula falsi (the
  // Illinois variant, which halves a stale end's value) needs half the
  // queries of halving the bracket twelve times (the tapered ball's plaque:
  // 14.5 -> 7 a call, 1.03 M -> 0.53 M queries); it halves where it has no
  // slope to follow (a cliff, an end on the level).
  const double width = (hi - lo) / 4096;
  int last_side = 0;
  for (int it = 0; it < 24 && hi - lo > width; ++it) {
    double t = 0.5 * (lo + hi);
    if (f_lo > 0 && f_hi < 0) {
      const double s = lo + (hi - lo) * (f_lo / (f_lo - f_hi));
      if (s > lo && s < hi) t = s;
    }
    const double f = above(t);
    if (f > 0) {
      lo = t;
      f_lo = f;
      if (last_side > 0) f_hi *= 0.5;
      last_side = 1;
    } else {
      hi = t;
      f_hi = f;
      if (last_side < 0) f_lo *= 0.5;
      last_side = -1;
    }
  }
  return hi;
}

// The chord a -> b (a at the level) sampled every `step` with the exact CL;
// samples the CL rises above are lifted onto it (on the lattice). Appends
// the points after a. The last resort of keep_level below. The lifted
// samples (a CL cliff's face, every step/5) are then fitted along the
// chord as a raster's row is (within `tolerance` above them, never below):
// a move between two vertices passes over the samples between, and over the
// samples left at the level, which lie under the level.
void append_lifted(const ClEngine& engine, const std::optional<XYLattice>& lat, const geometry::Vec3& a, const geometry::Vec3& b,
                   double level, double step, double tolerance, Polyline& out, std::size_t& queries) {
  const double len = xy_dist(a, b);
  const auto n = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(len / step)));
  const SampledLine line{a.x, a.y, b.x, b.y, n};
  Polyline chord{a};
  for (std::size_t k = 1; k < n; ++k) {
    // Only the samples the CL rises above the level at change anything.
    const std::size_t above = engine.first_above(line, k, n - 1, level);
    queries += (above < n ? above + 1 : n) - k;
    if (above >= n) break;
    k = above;
    geometry::Vec3 p{line.x(k), line.y(k), level};
    const double cl = engine.height_at(p.x, p.y);
    // The sample moves sideways out of the CL at the level, so the run
    // stays level for the band fit and the arcs: a sag of a micron or so
    // (the chord's ends are on the contour within that) by up to a step;
    // where the contour bulges out between its points (round an outside
    // corner of the part) by up to a quarter of the chord. Lifting over
    // such a bulge instead made a bump of hundredths of a millimetre
    // every few tenths (a line each, more than a serial link delivers).
    // The move to it from the point before must stay out of the CL too.
    if (len > 0) {
      const double nx = -(b.y - a.y) / len, ny = (b.x - a.x) / len;  // left: the free side
      const double limit = cl - level < kSmallSag ? step : std::max(step, 0.25 * len);
      const double d = free_offset(engine, p.x, p.y, nx, ny, level, 0, limit, queries);
      if (std::isfinite(d)) {
        const geometry::Vec3 q = on_lattice(engine, lat, {p.x + d * nx, p.y + d * ny, level}, queries);
        const geometry::Vec3& before = chord.back();
        ++queries;
        if (q.z == level && (cl - level < kSmallSag || before.z != level ||
                             engine.height_at(0.5 * (q.x + before.x), 0.5 * (q.y + before.y)) <= level)) {
          chord.push_back(q);
          continue;
        }
      }
    }
    p.z = cl;
    p = on_lattice(engine, lat, p, queries);
    // On the lattice the CL may be higher still: the point sits on it.
    ++queries;
    p.z = std::max(p.z, engine.height_at(p.x, p.y));
    chord.push_back(p);
  }
  chord.push_back(b);
  std::vector<double> us(chord.size()), zs(chord.size());
  bool increasing = true;
  for (std::size_t k = 0; k < chord.size(); ++k) {
    us[k] = xy_dist(a, chord[k]);
    zs[k] = chord[k].z;
    increasing = increasing && (k == 0 || us[k] > us[k - 1]);
  }
  if (chord.size() > 3 && increasing && tolerance > 0) {
    const std::vector<BandVertex> kept = fit_profile_in_band(us, zs, tolerance);
    for (std::size_t k = 1; k < kept.size(); ++k) out.push_back({chord[kept[k].index].x, chord[kept[k].index].y, kept[k].z});
  } else {
    out.insert(out.end(), chord.begin() + 1, chord.end());
  }
}

// How far the chord a -> b must move to its left (the free side) for the CL
// to stay at or below the level at every sample; 0 if it does already.
double push_needed(const ClEngine& engine, const geometry::Vec3& a, const geometry::Vec3& b, double level, double step,
                   std::size_t& queries) {
  const double len = xy_dist(a, b);
  if (!(len > 0)) return 0;
  const double nx = -(b.y - a.y) / len, ny = (b.x - a.x) / len;  // left normal
  const auto n = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(len / step)));
  const SampledLine line{a.x, a.y, b.x, b.y, n};
  double need = 0;
  for (std::size_t k = 1; k < n; ++k) {
    SampledLine pushed = line;
    pushed.ox = need * nx;
    pushed.oy = need * ny;
    const std::size_t above = engine.first_above(pushed, k, n - 1, level);
    queries += (above < n ? above + 1 : n) - k;
    if (above >= n) break;
    k = above;
    const double x = line.x(k), y = line.y(k);
    // Past four steps it is not a chord's sag: left to the lift.
    need = free_offset(engine, x, y, nx, ny, level, need, step * 4, queries);
    if (!std::isfinite(need)) return HUGE_VAL;
  }
  return need;
}

// A level run whose chords stay out of the CL: where the region is concave a
// chord between two contour points cuts into the part by its sag, so its
// points move sideways into the free region by what the exact CL says
// (microns), which keeps the run level (an arc fits it) and leaves at most
// that much. What a few rounds of that cannot clear is lifted instead.
Polyline keep_level(const ClEngine& engine, const std::optional<XYLattice>& lat, Polyline pts, bool closed,
                    double level, double step, double tolerance, std::size_t& queries) {
  const std::size_t n = pts.size();
  if (n < 2) return pts;
  const std::size_t chords = closed ? n : n - 1;
  // Only chords with an end moved in the round before are measured again
  // (the others are as they were: clear, or left to the lift).
  std::vector<std::uint8_t> dirty(chords, 1);
  for (int round = 0; round < 4; ++round) {
    std::vector<double> need(chords, 0);
    bool any = false;
    for (std::size_t c = 0; c < chords; ++c) {
      if (!dirty[c]) continue;
      need[c] = push_needed(engine, pts[c], pts[(c + 1) % n], level, step, queries);
      // A chord no push clears (a cliff of the CL) is left to the lift
      // below; the others still move (one cliff in a loop must not leave
      // every chord's micron sag to be lifted, which breaks the level).
      if (!std::isfinite(need[c])) need[c] = 0;
      any = any || need[c] > 0;
    }
    if (!any) break;
    // Each point moves along the bisector of its chords' left normals, far
    // enough for both.
    Polyline moved = pts;
    std::fill(dirty.begin(), dirty.end(), 0);
    for (std::size_t k = 0; k < n; ++k) {
      const bool has_prev = closed || k > 0, has_next = closed || k + 1 < n;
      const std::size_t cp = (k + chords - 1) % chords, cn = k % chords;
      const double dp = has_prev ? need[cp] : 0, dn = has_next ? need[cn] : 0;
      if (!(std::max(dp, dn) > 0)) continue;
      auto normal = [&](std::size_t c) {
        const geometry::Vec3 &a = pts[c], &b = pts[(c + 1) % n];
        const double len = xy_dist(a, b);
        return len > 0 ? std::pair{-(b.y - a.y) / len, (b.x - a.x) / len} : std::pair{0.0, 0.0};
      };
      auto [px, py] = has_prev ? normal(cp) : normal(cn);
      auto [qx, qy] = has_next ? normal(cn) : normal(cp);
      double bx = px + qx, by = py + qy;
      const double bl = std::hypot(bx, by);
      if (!(bl > 1e-9)) continue;
      bx /= bl;
      by /= bl;
      const double c = std::max(0.5, bx * px + by * py);
      const double d = std::max(dp, dn) / c;
      moved[k].x += d * bx;
      moved[k].y += d * by;
      if (has_prev) dirty[cp] = 1;
      if (has_next) dirty[cn] = 1;
    }
    pts = std::move(moved);
  }
  // Whatever still dips into the CL is lifted onto it, checked five times
  // as densely: where the CL has a cliff (an overhang of the part seen from
  // above) a chord can clip its corner between the samples above.
  for (geometry::Vec3& p : pts) p = on_lattice(engine, lat, p, queries);
  Polyline out{pts.front()};
  for (std::size_t c = 0; c < chords; ++c)
    append_lifted(engine, lat, pts[c], pts[(c + 1) % n], level, step / 5, tolerance, out, queries);
  return out;
}

struct Run {
  Polyline points;
  bool closed = false;  // a whole loop: may start at any of its points
};

// The contour's steep runs, in its own direction.
std::vector<Run> steep_runs(const LevelContour& c, const SlopeMap& slope, double angle) {
  const Polyline& p = c.points;
  const std::size_t n = p.size();
  std::vector<Run> out;
  if (n < 2) return out;
  std::vector<std::uint8_t> steep(n);
  std::size_t first_gentle = n;
  for (std::size_t k = 0; k < n; ++k) {
    steep[k] = slope.max_near(p[k].x, p[k].y) >= angle ? 1 : 0;
    if (!steep[k] && first_gentle == n) first_gentle = k;
  }
  if (c.closed && first_gentle == n) {
    out.push_back({p, true});
    return out;
  }
  // Walk from a gentle point (closed: all the way round) and cut at gentle points.
  const std::size_t start = c.closed ? first_gentle : 0;
  const std::size_t count = c.closed ? n + 1 : n;
  Polyline cur;
  for (std::size_t m = 0; m < count; ++m) {
    const std::size_t k = (start + m) % n;
    if (steep[k]) {
      // The run begins and ends at the gentle points beside it (the overlap).
      if (cur.empty() && m > 0) cur.push_back(p[(start + m - 1) % n]);
      cur.push_back(p[k]);
    } else if (!cur.empty()) {
      cur.push_back(p[k]);
      out.push_back({std::move(cur), false});
      cur.clear();
    }
  }
  if (cur.size() >= 2) out.push_back({std::move(cur), false});
  return out;
}

// How far above a flat area its level runs: clear of the flat's own CL
// (which the level's contour must not trace) by more than its flatness.
constexpr double kAboveFlat = 2e-3;

// The heights of the CL's flat areas: runs of level nodes (slope under half
// a degree) whose heights lie within a micron-scale band, covering at
// least min_area; each the band's highest height.
std::vector<double> flat_heights(const ClGrid& grid, const SlopeMap& slope, double min_area) {
  const double level = 0.5 * std::numbers::pi / 180, band = 1e-3;
  std::vector<double> z;
  for (std::size_t j = 0; j < grid.spec.ny; ++j)
    for (std::size_t i = 0; i < grid.spec.nx; ++i)
      if (slope.at(i, j) < level && !grid.on_floor[j * grid.spec.nx + i]) z.push_back(grid.at(i, j));
  std::sort(z.begin(), z.end());
  const auto need = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(min_area / (grid.spec.dx * grid.spec.dy))));
  std::vector<double> out;
  for (std::size_t i = 0; i < z.size();) {
    std::size_t j = i;
    while (j + 1 < z.size() && z[j + 1] - z[i] <= band) ++j;
    if (j - i + 1 >= need) {
      out.push_back(z[j]);
      i = j + 1;
    } else {
      ++i;
    }
  }
  return out;
}

// A node steep enough for the walls' spacing: the heights its slope spans
// (the slope map's differences reach its neighbours) and the sine of it.
struct WallNode {
  double lo, hi, sine;
};

std::vector<WallNode> wall_nodes(const ClGrid& grid, const SlopeMap& slope, double min_angle) {
  std::vector<WallNode> out;
  const std::size_t nx = grid.spec.nx, ny = grid.spec.ny;
  for (std::size_t j = 0; j < ny; ++j)
    for (std::size_t i = 0; i < nx; ++i) {
      const double a = slope.at(i, j);
      if (a < min_angle || grid.on_floor[j * nx + i]) continue;
      double lo = grid.at(i, j), hi = lo;
      auto take = [&](std::size_t ii, std::size_t jj) {
        lo = std::min(lo, grid.at(ii, jj));
        hi = std::max(hi, grid.at(ii, jj));
      };
      if (i > 0) take(i - 1, j);
      if (i + 1 < nx) take(i + 1, j);
      if (j > 0) take(i, j - 1);
      if (j + 1 < ny) take(i, j + 1);
      out.push_back({lo, hi, std::sin(a)});
    }
  return out;
}

// The band above z: as high as its gentlest wall node allows. Shrinking the
// band can only drop nodes, so the loop ends; every node left in it allows it.
double band_above(const std::vector<WallNode>& nodes, double z, double spacing) {
  double band = spacing;
  for (;;) {
    double sine = 1;
    for (const WallNode& n : nodes)
      if (n.hi > z && n.lo <= z + band) sine = std::min(sine, n.sine);
    const double allowed = spacing * sine;
    if (allowed >= band) return band;
    band = allowed;
  }
}

struct LevelPieces {
  std::vector<Run> runs;
  std::size_t contours = 0;
  std::size_t queries = 0;
};

}  // namespace

WaterlinePath build_waterline(const ClEngine& engine, const ClGrid& grid, const SlopeMap& slope,
                              const WaterlineOptions& o, const Checkpoint& checkpoint) {
  if (!(o.z_step > 0) || !(o.sample_step > 0) || !(o.tolerance >= 0))
    throw std::invalid_argument("waterline: the level step and the sample step must be positive");
  if (o.wall_spacing > 0 && !(o.wall_angle_deg > 0 && o.wall_angle_deg <= 90))
    throw std::invalid_argument("waterline: levels spaced by the walls need a wall angle in (0, 90] degrees");
  WaterlinePath out;
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  for (const double z : grid.z) {
    lo = std::min(lo, z);
    hi = std::max(hi, z);
  }
  if (!(hi > lo)) return out;
  // Levels from the foot of the walls (just above the lowest CL) upwards.
  const double bottom = std::max(o.bottom, lo + 1e-3);
  const double top = std::min(o.top, hi);
  // On the G-code's grid a level prints as it is. Half a step between two
  // printed values, a run's sub-micron lifts would print as Z steps of a
  // whole step, a line each.
  auto on_grid = [&](double z, bool up) {
    if (!o.lattice || !(o.lattice->step > 0)) return z;
    const double k = (z - o.lattice->z0) / o.lattice->step;
    return o.lattice->z0 + (up ? std::ceil(k) : std::floor(k)) * o.lattice->step;
  };
  const std::vector<WallNode> nodes =
      o.wall_spacing > 0 ? wall_nodes(grid, slope, o.wall_angle_deg * std::numbers::pi / 180) : std::vector<WallNode>{};
  for (double z = on_grid(bottom, true); z < top;) {
    out.levels.push_back(z);
    const double band = o.wall_spacing > 0 ? band_above(nodes, z, o.wall_spacing) : o.z_step;
    // Down onto the grid: a band never grows past what its walls allow.
    const double next = on_grid(z + band, false);
    if (out.levels.size() == 1) out.step_min = out.step_max = band;
    z = next > z ? next : z + band;
  }
  for (std::size_t k = 1; k < out.levels.size(); ++k) {
    const double gap = out.levels[k] - out.levels[k - 1];
    out.step_min = k == 1 ? gap : std::min(out.step_min, gap);
    out.step_max = k == 1 ? gap : std::max(out.step_max, gap);
  }
  if (o.flat_levels) {
    const double r = engine.cutter().radius;
    const double min_area = o.flat_min_area > 0 ? o.flat_min_area : std::numbers::pi * r * r / 4;
    for (const double f : flat_heights(grid, slope, min_area)) {
      const double z = on_grid(f + kAboveFlat, true);
      if (z < bottom || z >= top) continue;
      const bool near = std::any_of(out.levels.begin(), out.levels.end(),
                                    [&](double l) { return l >= f && l <= z + kAboveFlat; });
      if (!near) out.levels.push_back(z);
    }
    std::sort(out.levels.begin(), out.levels.end());
  }
  std::reverse(out.levels.begin(), out.levels.end());
  if (out.levels.empty()) return out;

  const double angle = o.steep_angle_deg * std::numbers::pi / 180;
  const PointQuery exact = [&engine](double x, double y) { return engine.height_at(x, y); };
  ContourOptions co;
  co.xy_tolerance = std::min(1e-3, o.tolerance > 0 ? o.tolerance : 1e-3);
  co.z_tolerance = co.xy_tolerance;

  std::vector<LevelPieces> levels(out.levels.size());
  std::atomic<std::size_t> done{0};
  tbb::parallel_for(std::size_t{0}, levels.size(), [&](std::size_t li) {
    const double z = out.levels[li];
    LevelPieces& lp = levels[li];
    const LevelContours lc = level_contours(grid, z, exact, co);
    lp.contours = lc.contours.size();
    lp.queries = lc.queries;
    for (const LevelContour& c : lc.contours)
      for (Run& r : steep_runs(c, slope, angle)) {
        // Every chord checked against the exact CL (closed loops: the closing
        // chord too; the loop then repeats its first point at its end).
        // A fitted move with a vertex moved off the contour is checked
        // against the exact CL as densely as the lifts are.
        const LevelMoveCheck clear = [&](const geometry::Vec3& a, const geometry::Vec3& b) {
          const auto n = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(xy_dist(a, b) / (o.sample_step / 5))));
          const std::size_t above = engine.first_above(SampledLine{a.x, a.y, b.x, b.y, n}, 0, n, z + kClearSlack);
          lp.queries += std::min(above, n) + 1;
          return above > n;
        };
        r.points = fit_level_run_in_band(
            keep_level(engine, o.lattice, std::move(r.points), r.closed, z, o.sample_step, o.simplify_tolerance,
                       lp.queries),
            o.simplify_tolerance, o.lattice, clear);
        lp.runs.push_back(std::move(r));
      }
    if (checkpoint) checkpoint(0.9 * double(++done) / double(levels.size()));
  });

  // Nearest first within a level, top level first; close pieces bridged.
  const double bridge_max = o.bridge_max > 0 ? o.bridge_max : 4 * engine.cutter().radius;
  bool have = false;
  geometry::Vec3 at;
  for (LevelPieces& lp : levels) {
    out.contours += lp.contours;
    out.point_queries += lp.queries;
    std::vector<char> used(lp.runs.size(), 0);
    for (std::size_t taken = 0; taken < lp.runs.size(); ++taken) {
      std::size_t best = 0, best_at = 0;
      double best_d = HUGE_VAL;
      for (std::size_t r = 0; r < lp.runs.size(); ++r) {
        if (used[r]) continue;
        const Polyline& p = lp.runs[r].points;
        // A closed loop (its last point repeats its first) may start at any point.
        const std::size_t starts = lp.runs[r].closed ? p.size() - 1 : 1;
        for (std::size_t s = 0; s < starts; ++s) {
          const double d = have ? xy_dist(at, p[s]) + std::fabs(at.z - p[s].z) : 0;
          if (d < best_d) {
            best_d = d;
            best = r;
            best_at = s;
          }
        }
      }
      used[best] = 1;
      Polyline piece;
      const Polyline& p = lp.runs[best].points;
      if (lp.runs[best].closed) {
        for (std::size_t k = 0; k + 1 < p.size(); ++k) piece.push_back(p[(best_at + k) % (p.size() - 1)]);
        piece.push_back(p[best_at]);
      } else {
        piece = p;
      }
      if (have && xy_dist(at, piece.front()) <= bridge_max && !out.pieces.empty()) {
        // Up, across, down, above every CL sample under the bridge.
        const geometry::Vec3 from = at, to = piece.front();
        double zb = std::max(from.z, to.z);
        const double len = xy_dist(from, to);
        const auto n = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(len / o.sample_step)));
        for (std::size_t k = 0; k <= n; ++k) {
          const double t = double(k) / double(n);
          zb = std::max(zb, engine.height_at(from.x + (to.x - from.x) * t, from.y + (to.y - from.y) * t));
          ++out.point_queries;
        }
        // Between samples a round cutter's CL sags at most step^2 / (8 rk)
        // under its chord; a flat one's gets a fixed margin, a V-bit's at
        // least the apex's slope times half a step.
        const Cutter& cut = engine.cutter();
        const double rk = cut.tip_round_radius();
        zb += rk > 0 ? o.sample_step * o.sample_step / (8 * rk) + 1e-3 : 0.05;
        if (cut.type == CutterType::VBit)
          zb += 0.5 * o.sample_step / std::tan(cut.half_angle_deg * std::numbers::pi / 180);
        Polyline& last = out.pieces.back();
        if (zb > from.z) last.push_back({from.x, from.y, zb});
        if (zb > to.z) last.push_back({to.x, to.y, zb});
        last.insert(last.end(), piece.begin(), piece.end());
      } else {
        out.pieces.push_back(std::move(piece));
      }
      at = out.pieces.back().back();
      have = true;
    }
  }
  if (checkpoint) checkpoint(1.0);
  return out;
}

}  // namespace cncstream::cam
