#pragma once
// The depth of cut of each move of a simulated program, per tool: the
// largest height drop of a stock node in one move, counting only nodes at
// least `rim` inside the cutter (the drop a cutter `rim` narrower would
// have taken). A node on the very rim of the footprint drops the whole
// height of the material beside it when the path moves by a micrometre
// (a lower level's loop nearer a wall than the one above by the arcs fitted
// to it, two-sided within the program's tolerance, or an arc's chords): a
// sliver that narrow is no depth of cut; set `rim` to the tolerance. A
// finishing cutter's rim can be set to the stock the roughing left (plus a
// little): its side cut of that skin along a wall is as tall as the wall.
#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "cncsim/removal.hpp"
#include "cncstream/cam/stock.hpp"

namespace simtest {

struct MoveDepth {
  double rim = 0.01;            // mm; at least the program's arc tolerance
  std::map<int, double> rim_of;  // per tool, where not `rim`
  std::map<int, double> deepest;  // per tool
  std::map<int, std::pair<cncstream::geometry::Vec3, cncstream::geometry::Vec3>> where;  // the move
  std::map<int, cncstream::geometry::Vec3> node;  // the node (x, y, its height before)

  // Cuts a -> b into `removal` with `cutter` (tool `tool`), noting the depth.
  void cut(cncsim::MaterialRemoval& removal, int tool, const cncstream::cam::Cutter& cutter, const cncstream::geometry::Vec3& a,
           const cncstream::geometry::Vec3& b) {
    const cncstream::cam::HeightFieldStock& s = removal.stock();
    if (std::min(a.z, b.z) >= s.top()) return removal.cut(a, b);  // above the stock: cuts nothing
    const cncstream::cam::GridSpec& g = s.grid();
    const double R = cutter.radius;
    const long i0 = std::max(0L, static_cast<long>(std::floor((std::min(a.x, b.x) - R - g.x0) / g.dx)));
    const long i1 = std::min(static_cast<long>(g.nx) - 1, static_cast<long>(std::ceil((std::max(a.x, b.x) + R - g.x0) / g.dx)));
    const long j0 = std::max(0L, static_cast<long>(std::floor((std::min(a.y, b.y) - R - g.y0) / g.dy)));
    const long j1 = std::min(static_cast<long>(g.ny) - 1, static_cast<long>(std::ceil((std::max(a.y, b.y) + R - g.y0) / g.dy)));
    before_.clear();
    for (long j = j0; j <= j1; ++j)
      for (long i = i0; i <= i1; ++i) before_.push_back(s.at(static_cast<std::size_t>(i), static_cast<std::size_t>(j)));
    removal.cut(a, b);
    if (s.nodes_cut() == 0) return;
    cncstream::cam::Cutter inner = cutter;
    inner.radius = cutter.radius - (rim_of.count(tool) ? rim_of.at(tool) : rim);
    inner.corner_radius = std::min(cutter.corner_radius, inner.radius);
    double& d = deepest[tool];
    std::size_t q = 0;
    for (long j = j0; j <= j1; ++j)
      for (long i = i0; i <= i1; ++i, ++q) {
        const double now = s.at(static_cast<std::size_t>(i), static_cast<std::size_t>(j));
        if (!(now < before_[q])) continue;
        const double low = std::max(now, cncstream::cam::swept_lowest_height(a, b, inner, g.x(static_cast<std::size_t>(i)),
                                                                        g.y(static_cast<std::size_t>(j))));
        if (before_[q] - low > d) {
          d = before_[q] - low;
          where[tool] = {a, b};
          node[tool] = {g.x(static_cast<std::size_t>(i)), g.y(static_cast<std::size_t>(j)), before_[q]};
        }
      }
  }

 private:
  std::vector<double> before_;
};

}  // namespace simtest
