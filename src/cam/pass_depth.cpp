// A pass's depth of cut in a height-field stock; see pass_depth.hpp.
#include "cncstream/cam/pass_depth.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "cncstream/cam/path_machining.hpp"

namespace cncstream::cam {

double stock_height_at(const HeightFieldStock& stock, double x, double y) {
  const GridSpec& g = stock.grid();
  const double fx = (x - g.x0) / g.dx, fy = (y - g.y0) / g.dy;
  const double last_i = static_cast<double>(g.nx - 1), last_j = static_cast<double>(g.ny - 1);
  if (!(fx >= 0 && fy >= 0 && fx <= last_i && fy <= last_j)) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t i = g.nx > 1 ? std::min(static_cast<std::size_t>(fx), g.nx - 2) : 0;
  const std::size_t j = g.ny > 1 ? std::min(static_cast<std::size_t>(fy), g.ny - 2) : 0;
  const double tx = g.nx > 1 ? fx - static_cast<double>(i) : 0, ty = g.ny > 1 ? fy - static_cast<double>(j) : 0;
  const std::size_t i1 = g.nx > 1 ? i + 1 : i, j1 = g.ny > 1 ? j + 1 : j;
  return (stock.at(i, j) * (1 - tx) + stock.at(i1, j) * tx) * (1 - ty) +
         (stock.at(i, j1) * (1 - tx) + stock.at(i1, j1) * tx) * ty;
}

namespace {

Cutter inner_cutter(const Cutter& cutter, double rim) {
  if (!(rim >= 0) || !(rim < cutter.radius))
    throw std::invalid_argument("pass depth: the rim left out must be at least 0 and less than the cutter radius");
  Cutter inner = cutter;
  inner.radius = cutter.radius - rim;
  inner.corner_radius = std::min(cutter.corner_radius, inner.radius);
  return inner;
}

// Notes a move's depth: the deepest, and the points along it when too deep.
void note(PassDepth& out, const MoveCut& m, double limit, double spacing) {
  const geometry::Vec3& low = m.a.z <= m.b.z ? m.a : m.b;
  if (m.depth > out.deepest) out.deepest = m.depth, out.at = low;
  if (!(m.depth > limit)) {
    out.deepest_within = std::max(out.deepest_within, m.depth);
    return;
  }
  out.too_deep.push_back(m);
  const auto n = static_cast<std::size_t>(std::ceil(std::hypot(m.b.x - m.a.x, m.b.y - m.a.y) / spacing));
  for (std::size_t k = 0; k <= n; ++k) {
    const double t = n ? static_cast<double>(k) / static_cast<double>(n) : 0.0;
    out.over.push_back({m.a.x + (m.b.x - m.a.x) * t, m.a.y + (m.b.y - m.a.y) * t, low.z});
  }
}

}  // namespace

PassDepth pass_depth(const HeightFieldStock& stock, const std::vector<Polyline>& pieces, const Cutter& cutter,
                     double rim, double limit, double retract_z) {
  const Cutter inner = inner_cutter(cutter, rim);
  Polyline moves;
  for (const Polyline& pl : pieces) {
    if (pl.empty()) continue;
    if (!moves.empty()) moves.push_back({moves.back().x, moves.back().y, retract_z});
    moves.push_back({pl.front().x, pl.front().y, retract_z});
    moves.insert(moves.end(), pl.begin(), pl.end());
  }
  PassDepth out;
  if (moves.empty()) return out;
  std::vector<MoveCut> cuts;
  (void)machine_path(stock.grid(), stock.heights(), {moves}, inner, cuts);
  // Points along a move too deep, a third of the radius apart: a window of
  // a radius around them covers where its cutter went.
  for (const MoveCut& m : cuts) note(out, m, limit, cutter.radius / 3);
  return out;
}


PassDepth pass_depth_bound(const HeightFieldStock& lower, const PassDepth& before, const Cutter& cutter, double rim,
                           double limit) {
  const Cutter inner = inner_cutter(cutter, rim);
  const GridSpec& g = lower.grid();
  PassDepth out;
  out.deepest = out.deepest_within = before.deepest_within;
  const double R = inner.radius;
  for (const MoveCut& m : before.too_deep) {
    MoveCut alone = m;
    alone.depth = 0;
    const auto clamp_i = [&](double v, std::size_t n) {
      return static_cast<std::size_t>(std::clamp(v, 0.0, static_cast<double>(n - 1)));
    };
    const std::size_t i0 = clamp_i(std::floor((std::min(m.a.x, m.b.x) - R - g.x0) / g.dx), g.nx);
    const std::size_t i1 = clamp_i(std::ceil((std::max(m.a.x, m.b.x) + R - g.x0) / g.dx), g.nx);
    const std::size_t j0 = clamp_i(std::floor((std::min(m.a.y, m.b.y) - R - g.y0) / g.dy), g.ny);
    const std::size_t j1 = clamp_i(std::ceil((std::max(m.a.y, m.b.y) + R - g.y0) / g.dy), g.ny);
    for (std::size_t j = j0; j <= j1; ++j)
      for (std::size_t i = i0; i <= i1; ++i) {
        const double low = swept_lowest_height(m.a, m.b, inner, g.x(i), g.y(j));
        if (std::isfinite(low)) alone.depth = std::max(alone.depth, lower.at(i, j) - low);
      }
    note(out, alone, limit, cutter.radius / 3);
  }
  return out;
}

}  // namespace cncstream::cam
