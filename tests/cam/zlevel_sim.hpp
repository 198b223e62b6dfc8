#pragma once
// Cuts a Z-level roughing path into a height-field stock the way a machine
// runs it (lifts, moves over, descents, cuts) and measures each move, and
// the bounds the tests hold a roughed result to.
#include <algorithm>
#include <cmath>
#include <vector>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/stock.hpp"
#include "cncstream/cam/zlevel_roughing.hpp"
#include "cam/cl_test_meshes.hpp"

namespace zlevel_test {

using namespace cncstream;

struct SimResult {
  double deepest_cut = 0;          // largest height drop of one feed move
  double rapid_removed = 0;        // deepest cut of a lift, move over or descent
  std::size_t moves = 0;
};

inline SimResult machine(cam::HeightFieldStock& stock, const cam::RoughingPath& path) {
  SimResult r;
  geometry::Vec3 at{path.levels.front().passes.front().points.front()};
  at.z = path.clearance_z;
  auto move = [&](const geometry::Vec3& to, bool rapid) {
    stock.cut_segment(at, to, path.cutter);
    ++r.moves;
    if (rapid) r.rapid_removed = std::max(r.rapid_removed, stock.last_max_depth());
    else r.deepest_cut = std::max(r.deepest_cut, stock.last_max_depth());
    at = to;
  };
  for (const auto& lv : path.levels)
    for (const auto& pass : lv.passes) {
      const geometry::Vec3& first = pass.points.front();
      if (pass.lift_before) {
        move({at.x, at.y, std::max(at.z, pass.lift_z)}, true);
        move({first.x, first.y, at.z}, true);
        move(first, true);
      } else {
        move(first, false);
      }
      for (std::size_t k = 1; k < pass.points.size(); ++k) move(pass.points[k], false);
    }
  move({at.x, at.y, path.clearance_z}, true);
  return r;
}

// Upper bound of what the roughing cutter leaves over the nodes of `grid`
// with its tip at every allowed height of a node grid `tips` around it (the
// grown CL plus leave, +inf where the tip may not go): `tips` has `pad` more
// nodes on each side of `grid`, same spacing. Capped at `top`.
inline std::vector<double> ideal_surface(const cam::GridSpec& grid, std::size_t pad, const std::vector<double>& tips,
                                         const cam::Cutter& c, double top) {
  std::vector<double> s(grid.size(), top);
  const std::size_t tnx = grid.nx + 2 * pad, tny = grid.ny + 2 * pad;
  const long rn = static_cast<long>(std::ceil(c.radius / grid.dx));
  for (std::size_t j = 0; j < grid.ny; ++j)
    for (std::size_t i = 0; i < grid.nx; ++i) {
      double best = top;
      for (long dj = -rn; dj <= rn; ++dj)
        for (long di = -rn; di <= rn; ++di) {
          const long ii = static_cast<long>(i + pad) + di, jj = static_cast<long>(j + pad) + dj;
          if (ii < 0 || jj < 0 || ii >= static_cast<long>(tnx) || jj >= static_cast<long>(tny)) continue;
          const double rho = std::hypot(static_cast<double>(di) * grid.dx, static_cast<double>(dj) * grid.dy);
          if (rho > c.radius) continue;
          const double t = tips[static_cast<std::size_t>(jj) * tnx + static_cast<std::size_t>(ii)];
          best = std::min(best, t + c.profile_height(rho));
        }
      s[j * grid.nx + i] = best;
    }
  return s;
}

// A block [-30, 30] x [-25, 25] x [0, 20] with a pocket [-15, 15] x
// [-10, 10] down to z = 10, vertical walls.
inline geometry::Mesh pocket_block() {
  std::vector<std::array<geometry::Vec3, 3>> t;
  auto quad = [&](geometry::Vec3 a, geometry::Vec3 b, geometry::Vec3 c, geometry::Vec3 d) {
    t.push_back({a, b, c});
    t.push_back({a, c, d});
  };
  auto top = [&](double x0, double y0, double x1, double y1, double z) {
    quad({x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z});
  };
  top(-30, -25, 30, 25, 0);
  top(-30, -25, -15, 25, 20);
  top(15, -25, 30, 25, 20);
  top(-15, -25, 15, -10, 20);
  top(-15, 10, 15, 25, 20);
  top(-15, -10, 15, 10, 10);
  auto wall = [&](double x0, double y0, double x1, double y1, double z0, double z1) {
    quad({x0, y0, z0}, {x1, y1, z0}, {x1, y1, z1}, {x0, y0, z1});
  };
  wall(-30, -25, 30, -25, 0, 20);
  wall(30, -25, 30, 25, 0, 20);
  wall(30, 25, -30, 25, 0, 20);
  wall(-30, 25, -30, -25, 0, 20);
  wall(-15, -10, 15, -10, 10, 20);
  wall(15, -10, 15, 10, 10, 20);
  wall(15, 10, -15, 10, 10, 20);
  wall(-15, 10, -15, -10, 10, 20);
  return cl_test::welded(t);
}

}  // namespace zlevel_test
