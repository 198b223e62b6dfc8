#include "cncstream/cam/raster.hpp"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <optional>
#include <stdexcept>

#include "cncstream/cam/polyline_simplify.hpp"

namespace cncstream::cam {

XYBounds default_bounds(const geometry::Mesh& mesh, const Cutter& cutter) {
  const geometry::Box3 b = mesh.bounds();
  if (b.empty()) throw std::invalid_argument("mesh has no facets");
  return {b.lo.x - cutter.radius, b.lo.y - cutter.radius, b.hi.x + cutter.radius, b.hi.y + cutter.radius};
}

namespace {

// n + 1 evenly spaced values from a to b with spacing at most `max_step`.
std::size_t intervals(double length, double max_step) {
  return std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(length / max_step - 1e-9)));
}

// Positions 0 = s_0 < ... < s_n = length along one axis. Without a lattice
// (lat = 0) evenly spread with spacing at most max_step. With one: uniform
// spacing d, the largest lattice multiple not above max_step (at least one
// lattice step), and a shorter last interval where length is not a multiple
// of d. `uniform` is how many leading positions are k * d (all of them
// without a lattice).
struct AxisSamples {
  std::vector<double> s;
  std::size_t uniform = 0;
  double d = 0;
};

AxisSamples axis_samples(double length, double max_step, double lat) {
  AxisSamples a;
  if (!(length > 0)) {
    a.s = {0.0};
    a.uniform = 1;
    return a;
  }
  if (lat <= 0) {
    const std::size_t n = intervals(length, max_step);
    a.d = length / double(n);
    for (std::size_t k = 0; k <= n; ++k) a.s.push_back(k == n ? length : double(k) * a.d);
    a.uniform = a.s.size();
    return a;
  }
  a.d = std::max(1.0, std::floor(max_step / lat + 1e-9)) * lat;
  const auto n = static_cast<std::size_t>(std::floor(length / a.d + 1e-9));
  for (std::size_t k = 0; k <= n; ++k) a.s.push_back(double(k) * a.d);
  a.uniform = a.s.size();
  if (length - a.s.back() > 0.5 * lat) a.s.push_back(length);
  return a;
}

// Rows spaced by the ground between them: from each row the farthest next
// one the gap allows (a lattice multiple, at least one lattice step), the
// last at `length`. Spacings are rounded down to a quantum (a lattice
// multiple) so that runs of rows share one spacing, and so one CL grid.
AxisSamples gap_samples(double length, double widest, double lat, double v0,
                        const std::function<double(double, double)>& gap) {
  AxisSamples a;
  a.s = {0.0};
  const double unit = lat > 0 ? lat : 1e-6;
  const double quantum = std::max(unit, std::floor(widest / 32 / unit) * unit);
  while (a.s.back() < length - 0.5 * unit) {
    const double from = a.s.back();
    double d = std::min(widest, length - from);
    // The gap only grows as the band narrows: a few rounds settle it.
    for (int round = 0; round < 8; ++round) {
      const double allowed = std::min(widest, gap(v0 + from, v0 + from + d));
      if (d <= allowed) break;
      d = allowed;
    }
    if (from + d < length - 0.5 * unit) {
      // (A gap under the quantum, on ground nearly as steep as allowed, on the lattice only.)
      const double q = d >= quantum ? quantum : unit;
      d = std::max(unit, std::floor(d / q + 1e-9) * q);
    }
    a.s.push_back(std::min(length, from + d));
  }
  a.uniform = 0;  // bands are found by the caller
  return a;
}

// Bounds snapped inward onto the lattice through `origin` (unchanged without one).
std::pair<double, double> snap_inward(double lo, double hi, double origin, double lat) {
  if (lat <= 0) return {lo, hi};
  const double a = origin + std::ceil((lo - origin) / lat - 1e-9) * lat;
  const double b = origin + std::floor((hi - origin) / lat + 1e-9) * lat;
  return b >= a ? std::pair{a, b} : std::pair{a, a};
}

// A sample of the CL profile along a pass. stair_z: the move into this
// sample from the previous one crosses a step narrower than the path can
// resolve (one lattice step): it is made as a staircase at stair_z (up, across,
// down) instead of a diagonal that would shave the wall beside the step.
struct Sample {
  double u, z;
  double stair_z = -HUGE_VAL;
  bool stair() const { return stair_z > -HUGE_VAL; }
};

// Between two exact CL samples the CL surface can rise above the chord only
// where it bends down: by at most L^2 / (8 rk) for a chord of length L (the
// offsets of a cutter with corner radius rk curve no tighter than rk), except
// at vertical steps beside walls; a flat end's surface has no bound. Such
// suspicious intervals get an exact point query at their midpoint; where the
// surface is off the chord there by more than eps (measured across the
// chord), the midpoint is kept and both halves are examined the same way.
// Samples from another engine (a grid_source) stand above the exact surface
// by up to its error: there a midpoint is kept when it is above the chord
// (the chord would cut into the part) or lower than that error allows (a
// wall's step is in the interval), or every interval would be split.
struct StepRefiner {
  const ClEngine& engine;
  double rk;
  double lattice = 0;       // midpoints are snapped to multiples of this (0: exact halves)
  double below_allowance = 0;  // > 0: how far (vertically) the samples may stand above the exact surface
  double eps = 1e-4;        // mm of possible chord sag accepted
  double min_width = 1e-4;  // mm; narrower intervals are not split (no lattice)

  bool suspicious(double du, double dz) const {
    if (rk > 0) return (du * du + dz * dz) / (8 * rk) > eps;
    // A flat end's CL surface is not curvature-bounded: where an edge's
    // contact meets the plateau of its end vertex it bends sharply even on a
    // gentle slope. Only level intervals (plateaus) are certainly straight.
    return std::fabs(dz) > 1e-9;
  }

  // Distance from the surface point (um, zm) to the chord, measured across
  // the chord (how deep the cutter would cut): a vertical error on a
  // near-vertical part of the CL surface is a sideways nick of a fraction of it.
  bool off_chord(double ua, double za, double ub, double zb, double um, double zm) const {
    const double slope = (zb - za) / (ub - ua);
    const double chord = za + slope * (um - ua);
    if (below_allowance > 0) return (zm - chord) / std::sqrt(1 + slope * slope) > eps || chord - zm > below_allowance;
    return std::fabs(zm - chord) / std::sqrt(1 + slope * slope) > eps;
  }

  // Appends the samples of (ua, ub], refined, ending with (ub, zb).
  template <class At>
  void refine(double ua, double za, double ub, double zb, At at, std::vector<Sample>& out, std::size_t& queries) const {
    const double du = ub - ua;
    if (!suspicious(du, zb - za)) {
      out.push_back({ub, zb});
      return;
    }
    // ua and ub are lattice multiples; so must a kept midpoint be, strictly inside.
    const double n = lattice > 0 ? std::round(du / lattice) : 0;
    const bool splittable = lattice > 0 ? n >= 2 : du >= min_width;
    const double um = !splittable || lattice <= 0 ? 0.5 * (ua + ub) : ua + std::floor(n / 2) * lattice;
    const double zm = at(um);
    ++queries;
    if (!off_chord(ua, za, ub, zb, um, zm)) {
      out.push_back({ub, zb});
      return;
    }
    if (!splittable) {
      out.push_back({ub, zb, std::max({za, zb, zm})});
      return;
    }
    refine(ua, za, um, zm, at, out, queries);
    refine(um, zm, ub, zb, at, out, queries);
  }
};

// Exact CL samples along a straight pass (u = distance along it) -> the
// refined polyline fitted inside the band [CL, CL + tolerance] (vertices
// above their samples, not on them: on convex stretches the moves are
// sqrt(8 R T) long instead of the sample spacing), mapped to points by
// `to_point`. Runs between staircases are fitted separately (the staircase
// corners are kept).
template <class At, class ToPoint>
Polyline pass_polyline(const std::vector<double>& us_in, const std::vector<double>& zs_in, const StepRefiner& refiner,
                       double tolerance, At at, ToPoint to_point, std::size_t& queries) {
  std::vector<Sample> all;
  all.reserve(us_in.size() + 16);
  for (std::size_t k = 0; k < us_in.size(); ++k) {
    if (k == 0) all.push_back({us_in[0], zs_in[0]});
    else refiner.refine(all.back().u, all.back().z, us_in[k], zs_in[k], at, all, queries);
  }
  Polyline out;
  std::vector<double> us, zs;
  auto flush = [&] {
    for (const BandVertex& v : fit_profile_in_band(us, zs, tolerance)) out.push_back(to_point(us[v.index], v.z));
    us.clear();
    zs.clear();
  };
  for (const Sample& smp : all) {
    if (smp.stair()) {
      const double ua = us.back(), za = zs.back();
      flush();
      if (smp.stair_z > za) out.push_back(to_point(ua, smp.stair_z));
      if (smp.stair_z > smp.z) out.push_back(to_point(smp.u, smp.stair_z));
    }
    us.push_back(smp.u);
    zs.push_back(smp.z);
  }
  flush();
  return out;
}

}  // namespace

RasterPath build_raster(const ClEngine& engine, const XYBounds& b, const RasterOptions& o, const Checkpoint& checkpoint) {
  if (!(o.stepover > 0)) throw std::invalid_argument("stepover must be positive");
  if (!(o.tolerance >= 0)) throw std::invalid_argument("tolerance must not be negative");
  if (o.check_subdivisions < 1) throw std::invalid_argument("check_subdivisions must be at least 1");
  const double step = o.step > 0 ? o.step : std::min(o.stepover / 4, 0.1);
  if (!(b.x1 >= b.x0) || !(b.y1 >= b.y0)) throw std::invalid_argument("raster bounds are empty");
  const double lat = o.lattice ? o.lattice->step : 0;
  if (o.lattice && !(lat > 0)) throw std::invalid_argument("lattice step must be positive");

  const bool along_x = o.direction == RasterDirection::X;
  // u runs along the rows, v across them.
  // Plain variables, not structured bindings: the lambdas below capture them
  // (clang before 16, and so clang-tidy 14, refuses to capture a binding).
  const auto u_range = snap_inward(along_x ? b.x0 : b.y0, along_x ? b.x1 : b.y1,
                                   o.lattice ? (along_x ? o.lattice->x0 : o.lattice->y0) : 0, lat);
  const auto v_range = snap_inward(along_x ? b.y0 : b.x0, along_x ? b.y1 : b.x1,
                                   o.lattice ? (along_x ? o.lattice->y0 : o.lattice->x0) : 0, lat);
  const double u0 = u_range.first, u1 = u_range.second, v0 = v_range.first, v1 = v_range.second;
  // Without a lattice: nu - 1 = whole steps times subdivisions, evenly spread.
  const AxisSamples us_axis =
      lat > 0 ? axis_samples(u1 - u0, step / o.check_subdivisions, lat)
              : axis_samples(u1 - u0, (u1 - u0) / double(intervals(u1 - u0, step) * std::size_t(o.check_subdivisions)), 0);
  if (o.row_gap && o.keep_grid) throw std::invalid_argument("keep_grid needs evenly spaced rows (no row_gap)");
  const AxisSamples vs_axis =
      o.row_gap ? gap_samples(v1 - v0, o.stepover, lat, v0, o.row_gap) : axis_samples(v1 - v0, o.stepover, lat);
  const std::size_t nu = us_axis.s.size(), nrows = vs_axis.s.size();
  const double du = us_axis.d;

  // Progress: the CL grids are the first half of the work, the rows the second.
  // Uniform columns come from CL grids, a shorter last column from point
  // queries. Runs of rows with one spacing share a grid (even rows: one,
  // and a one-row grid for a shorter last row).
  auto grid_for = [&](double v_first, std::size_t rows, double v_step, const Checkpoint& cp) {
    GridSpec spec;
    spec.nx = along_x ? us_axis.uniform : rows;
    spec.ny = along_x ? rows : us_axis.uniform;
    spec.x0 = along_x ? u0 : v_first;
    spec.y0 = along_x ? v_first : u0;
    spec.dx = along_x ? (du > 0 ? du : 1) : (v_step > 0 ? v_step : 1);
    spec.dy = along_x ? (v_step > 0 ? v_step : 1) : (du > 0 ? du : 1);
    return o.grid_source ? o.grid_source(spec, cp) : engine.compute(spec, cp);
  };
  struct Band {
    std::size_t first = 0, count = 0;
    ClGrid grid;
  };
  std::vector<Band> bands;
  std::vector<std::size_t> band_of(nrows);
  for (std::size_t r = 0; r < nrows;) {
    std::size_t e = r;  // last row of the band
    if (!o.row_gap) {
      e = r < vs_axis.uniform ? vs_axis.uniform - 1 : r;
    } else if (r + 1 < nrows) {
      const double d = vs_axis.s[r + 1] - vs_axis.s[r];
      e = r + 1;
      while (e + 1 < nrows && std::fabs(vs_axis.s[e + 1] - vs_axis.s[e] - d) < 1e-9) ++e;
    }
    for (std::size_t k = r; k <= e; ++k) band_of[k] = bands.size();
    bands.push_back({r, e - r + 1, {}});
    r = e + 1;
  }
  std::size_t rows_gridded = 0;
  for (Band& band : bands) {
    const std::size_t last = band.first + band.count - 1;
    const double d = !o.row_gap && band.count > 1 ? vs_axis.d
                     : band.count > 1             ? (vs_axis.s[last] - vs_axis.s[band.first]) / double(band.count - 1)
                                                  : 1;
    Checkpoint cp;
    if (checkpoint)
      cp = [&, before = rows_gridded, n = band.count](double f) {
        checkpoint(0.5 * (double(before) + f * double(n)) / double(nrows));
      };
    band.grid = grid_for(v0 + vs_axis.s[band.first], band.count, d, cp);
    rows_gridded += band.count;
  }
  // A row's across coordinate is its grid's (the same value for even rows).
  std::vector<double> row_v(nrows);
  for (std::size_t r = 0; r < nrows; ++r) {
    const Band& band = bands[band_of[r]];
    row_v[r] = along_x ? band.grid.spec.y(r - band.first) : band.grid.spec.x(r - band.first);
  }

  RasterPath path;
  path.bounds = along_x ? XYBounds{u0, v0, u1, v1} : XYBounds{v0, u0, v1, u1};
  path.stepover = 0;
  path.stepover_min = HUGE_VAL;
  for (std::size_t r = 0; r + 1 < nrows; ++r) {
    const double d = vs_axis.s[r + 1] - vs_axis.s[r];
    path.stepover = std::max(path.stepover, d);
    // The last interval may be shorter (the bounds' end).
    if (r + 2 < nrows || nrows == 2) path.stepover_min = std::min(path.stepover_min, d);
  }
  if (!o.row_gap) path.stepover = vs_axis.d;
  if (!o.row_gap || !std::isfinite(path.stepover_min)) path.stepover_min = path.stepover;
  path.step = du * o.check_subdivisions;
  path.samples = nu * nrows;

  auto point = [&](double u, double v, double z) { return along_x ? geometry::Vec3{u, v, z} : geometry::Vec3{v, u, z}; };
  auto query = [&](double u, double v) {
    const geometry::Vec3 p = point(u, v, 0);
    return engine.height_at(p.x, p.y);
  };
  const StepRefiner refiner{engine, engine.cutter().corner_radius, lat};
  path.rows.resize(nrows);
  std::vector<std::size_t> row_queries(nrows, 0), row_raised(nrows, 0);
  // Rows are independent: refine and merge them in parallel.
  auto do_row = [&](std::size_t r) {
    const double v = row_v[r];
    const bool forward = r % 2 == 0;
    const Band& band = bands[band_of[r]];
    auto cl = [&](std::size_t k) {
      if (k >= us_axis.uniform) return query(u0 + us_axis.s[k], v);
      const std::size_t gr = r - band.first;
      return along_x ? band.grid.at(k, gr) : band.grid.at(gr, k);
    };
    // s: distance travelled along the row, a lattice multiple like u - u0 and u1 - u.
    std::vector<double> ss(nu), zs(nu);
    for (std::size_t k = 0; k < nu; ++k) {
      const std::size_t idx = forward ? k : nu - 1 - k;
      ss[k] = forward ? us_axis.s[idx] : us_axis.s.back() - us_axis.s[idx];
      zs[k] = cl(idx);
    }
    auto along = [&](double s) { return forward ? u0 + s : u0 + (us_axis.s.back() - s); };
    // Another engine's grid can be below the exact surface (the depth
    // buffer in the slivers beside walls): there the exact height decides,
    // before the row is refined (a wall's step is found where it is).
    StepRefiner row_refiner = refiner;
    if (o.grid_source) {
      double above = 0;  // the most a node stands above the exact surface
      for (std::size_t k = 0; k < nu; ++k) {
        const double e = query(along(ss[k]), v);
        if (e > zs[k]) zs[k] = e, ++row_raised[r];
        above = std::max(above, zs[k] - e);
      }
      row_refiner.below_allowance = 2 * above + row_refiner.eps;
    }
    path.rows[r] = pass_polyline(
        ss, zs, row_refiner, o.tolerance, [&](double s) { return query(along(s), v); },
        [&](double s, double z) { return point(along(s), v, z); }, row_queries[r]);
  };
  std::atomic<std::size_t> rows_done{0};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nrows, 1), [&](const tbb::blocked_range<std::size_t>& rr) {
    for (std::size_t r = rr.begin(); r != rr.end(); ++r) {
      do_row(r);
      if (checkpoint) checkpoint(0.5 + 0.5 * double(++rows_done) / double(nrows));
    }
  });
  const std::size_t steps_per_row =
      lat > 0 ? std::size_t(std::ceil((u1 - u0) / (du * o.check_subdivisions) - 1e-9)) + 1
              : (nu - 1) / std::size_t(o.check_subdivisions) + 1;
  for (std::size_t r = 0; r < nrows; ++r) {
    path.points_before_merge += steps_per_row;
    path.points_after_merge += path.rows[r].size();
    path.refinement_queries += row_queries[r];
    path.raised_to_exact += row_raised[r];
  }

  // Links between rows run across them at the row ends, sampled with point
  // queries at the check step and refined like the rows.
  const double dl = du > 0 ? du : step / o.check_subdivisions;
  for (std::size_t r = 0; r + 1 < nrows; ++r) {
    const geometry::Vec3 a = path.rows[r].back();
    const double u = along_x ? a.x : a.y;
    const double va = row_v[r];
    auto at = [&](double s) { return query(u, va + s); };
    const std::vector<double> s = axis_samples(row_v[r + 1] - va, dl, lat).s;
    std::vector<double> z(s.size());
    for (std::size_t k = 0; k < s.size(); ++k) z[k] = at(s[k]);
    path.samples += s.size();
    path.links.push_back(pass_polyline(
        s, z, refiner, o.tolerance, at, [&](double sv, double zz) { return point(u, va + sv, zz); },
        path.refinement_queries));
  }
  if (o.keep_grid) path.grid = std::move(bands.front().grid);
  return path;
}

}  // namespace cncstream::cam
