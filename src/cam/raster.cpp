#include "cncstream/cam/raster.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <thread>

#include "cncstream/cam/polyline_simplify.hpp"

namespace cncstream {

XYBounds default_bounds(const Mesh& mesh, const Cutter& cutter) {
  const Box3 b = mesh.bounds();
  if (b.empty()) throw std::invalid_argument("mesh has no facets");
  return {b.lo.x - cutter.radius, b.lo.y - cutter.radius, b.hi.x + cutter.radius, b.hi.y + cutter.radius};
}

namespace {

// n + 1 evenly spaced values from a to b with spacing at most `max_step`.
std::size_t intervals(double length, double max_step) {
  return std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(length / max_step - 1e-9)));
}

// Simplify a profile sampled at (u_k, z_k) and map the kept samples back to
// points via `to_point`.
template <class ToPoint>
Polyline simplified(const std::vector<double>& u, const std::vector<double>& z, double tol, ToPoint to_point) {
  Polyline out;
  for (std::size_t k : simplify_profile_above(u, z, tol)) out.push_back(to_point(u[k], z[k]));
  return out;
}

// Between two exact CL samples the CL surface can rise above the chord only
// where it bends down: by at most L^2 / (8 rk) for a chord of length L (the
// offsets of a cutter with corner radius rk curve no tighter than rk), except
// at vertical steps beside walls; a flat end's surface has no bound. Such
// suspicious intervals get an exact point query at their midpoint; where the
// surface is off the chord there by more than eps (measured across the
// chord), the midpoint is kept and both halves are examined the same way.
struct StepRefiner {
  const ClEngine& engine;
  double rk;
  double eps = 1e-4;        // mm of possible chord sag accepted
  double min_width = 1e-4;  // mm; narrower intervals are left (a sub-micron side nick at most)

  bool suspicious(double du, double dz) const {
    if (rk > 0) return (du * du + dz * dz) / (8 * rk) > eps;
    // A flat end's CL surface is not curvature-bounded: where an edge's
    // contact meets the plateau of its end vertex it bends sharply even on a
    // gentle slope. Only level intervals (plateaus) are certainly straight.
    return std::fabs(dz) > 1e-9;
  }

  // Appends refined samples strictly inside (ua, ub) to out, in order.
  template <class At>
  void refine(double ua, double za, double ub, double zb, At at, std::vector<std::pair<double, double>>& out,
              std::size_t& queries) const {
    const double du = ub - ua;
    if (du < min_width || !suspicious(du, zb - za)) return;
    const double um = 0.5 * (ua + ub);
    const double zm = at(um);
    ++queries;
    // Distance from the surface point to the chord, measured across the chord
    // (how deep the cutter would cut): a vertical error on a near-vertical
    // part of the CL surface is a sideways nick of a fraction of it.
    const double slope = (zb - za) / du;
    if (std::fabs(zm - 0.5 * (za + zb)) / std::sqrt(1 + slope * slope) <= eps) return;
    refine(ua, za, um, zm, at, out, queries);
    out.emplace_back(um, zm);
    refine(um, zm, ub, zb, at, out, queries);
  }
};

// Exact CL samples along a straight pass (u = distance along it) -> the
// refined and merged polyline, mapped to points by `to_point`.
template <class At, class ToPoint>
Polyline pass_polyline(const std::vector<double>& us_in, const std::vector<double>& zs_in, const StepRefiner& refiner,
                       double tolerance, At at, ToPoint to_point, std::size_t& queries) {
  std::vector<double> us, zs;
  us.reserve(us_in.size() + 16);
  zs.reserve(zs_in.size() + 16);
  std::vector<std::pair<double, double>> extra;
  for (std::size_t k = 0; k < us_in.size(); ++k) {
    if (k > 0) {
      extra.clear();
      refiner.refine(us.back(), zs.back(), us_in[k], zs_in[k], at, extra, queries);
      for (const auto& [eu, ez] : extra) {
        us.push_back(eu);
        zs.push_back(ez);
      }
    }
    us.push_back(us_in[k]);
    zs.push_back(zs_in[k]);
  }
  return simplified(us, zs, tolerance, to_point);
}

}  // namespace

RasterPath build_raster(const ClEngine& engine, const XYBounds& b, const RasterOptions& o) {
  if (!(o.stepover > 0)) throw std::invalid_argument("stepover must be positive");
  if (!(o.tolerance >= 0)) throw std::invalid_argument("tolerance must not be negative");
  if (o.check_subdivisions < 1) throw std::invalid_argument("check_subdivisions must be at least 1");
  const double step = o.step > 0 ? o.step : std::min(o.stepover / 4, 0.1);
  if (!(b.x1 >= b.x0) || !(b.y1 >= b.y0)) throw std::invalid_argument("raster bounds are empty");

  const bool along_x = o.direction == RasterDirection::X;
  // u runs along the rows, v across them.
  const double u0 = along_x ? b.x0 : b.y0, u1 = along_x ? b.x1 : b.y1;
  const double v0 = along_x ? b.y0 : b.x0, v1 = along_x ? b.y1 : b.x1;
  const std::size_t nrows = intervals(v1 - v0, o.stepover) + 1;
  const double dv = nrows > 1 ? (v1 - v0) / double(nrows - 1) : 0;
  const std::size_t nu = intervals(u1 - u0, step) * std::size_t(o.check_subdivisions) + 1;
  const double du = nu > 1 ? (u1 - u0) / double(nu - 1) : 0;

  GridSpec spec;
  spec.nx = along_x ? nu : nrows;
  spec.ny = along_x ? nrows : nu;
  spec.x0 = b.x0;
  spec.y0 = b.y0;
  spec.dx = along_x ? (du > 0 ? du : 1) : (dv > 0 ? dv : 1);
  spec.dy = along_x ? (dv > 0 ? dv : 1) : (du > 0 ? du : 1);
  const ClGrid grid = engine.compute(spec);

  RasterPath path;
  path.bounds = b;
  path.stepover = dv;
  path.step = du * o.check_subdivisions;
  path.samples = grid.z.size();

  auto point = [&](double u, double v, double z) { return along_x ? Vec3{u, v, z} : Vec3{v, u, z}; };
  const StepRefiner refiner{engine, engine.cutter().corner_radius};
  path.rows.resize(nrows);
  std::vector<std::size_t> row_queries(nrows, 0);
  // Rows are independent: refine and merge them in parallel.
  auto do_row = [&](std::size_t r) {
    const double v = v0 + double(r) * dv;
    const bool forward = r % 2 == 0;
    std::vector<double> us(nu), zs(nu);
    for (std::size_t k = 0; k < nu; ++k) {
      const std::size_t idx = forward ? k : nu - 1 - k;
      us[k] = double(k) * du;  // distance travelled along the row
      zs[k] = along_x ? grid.at(idx, r) : grid.at(r, idx);
    }
    auto along = [&](double s) { return forward ? u0 + s : u1 - s; };
    path.rows[r] = pass_polyline(
        us, zs, refiner, o.tolerance,
        [&](double s) {
          const Vec3 p = point(along(s), v, 0);
          return engine.height_at(p.x, p.y);
        },
        [&](double s, double z) { return point(along(s), v, z); }, row_queries[r]);
  };
  const unsigned nthreads = std::max(1u, std::min<unsigned>(std::thread::hardware_concurrency(), 8));
  std::atomic<std::size_t> next{0};
  std::vector<std::thread> pool;
  for (unsigned t = 0; t + 1 < nthreads; ++t)
    pool.emplace_back([&] {
      for (std::size_t r; (r = next++) < nrows;) do_row(r);
    });
  for (std::size_t r; (r = next++) < nrows;) do_row(r);
  for (auto& th : pool) th.join();
  for (std::size_t r = 0; r < nrows; ++r) {
    path.points_before_merge += (nu - 1) / std::size_t(o.check_subdivisions) + 1;
    path.points_after_merge += path.rows[r].size();
    path.refinement_queries += row_queries[r];
  }

  // Links between rows run across them at the row ends, sampled with point
  // queries at the check step and refined like the rows.
  const double dl = du > 0 ? du : step / o.check_subdivisions;
  for (std::size_t r = 0; r + 1 < nrows; ++r) {
    const Vec3 a = path.rows[r].back();
    const double u = along_x ? a.x : a.y;
    const double va = v0 + double(r) * dv;
    const std::size_t n = intervals(dv, dl) + 1;
    auto at = [&](double s) {
      const Vec3 p = point(u, va + s, 0);
      return engine.height_at(p.x, p.y);
    };
    std::vector<double> s(n), z(n);
    for (std::size_t k = 0; k < n; ++k) {
      s[k] = dv * double(k) / double(n - 1);
      z[k] = at(s[k]);
    }
    path.samples += n;
    path.links.push_back(pass_polyline(
        s, z, refiner, o.tolerance, at, [&](double sv, double zz) { return point(u, va + sv, zz); },
        path.refinement_queries));
  }
  return path;
}

}  // namespace cncstream
