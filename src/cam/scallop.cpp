#include "cncstream/cam/scallop.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace cncstream::cam {

ScallopStats scallop_stats(const std::vector<double>& values) {
  ScallopStats s;
  double sum = 0;
  s.min = HUGE_VAL;
  s.max = -HUGE_VAL;
  for (double v : values) {
    if (!std::isfinite(v)) continue;
    s.min = std::min(s.min, v);
    s.max = std::max(s.max, v);
    sum += v;
    ++s.samples;
  }
  if (s.samples == 0) return {};
  s.mean = sum / double(s.samples);
  return s;
}

ScallopMap scallops_from_cut(const GridSpec& g, const std::vector<double>& machined, const DesignHeights& design,
                             const std::vector<double>& rows, bool along_x, const std::vector<double>* reach) {
  if (machined.size() != g.size() || design.z.size() != g.size() || (reach && reach->size() != g.size()))
    throw std::invalid_argument("scallops_from_cut: grid sizes differ");
  ScallopMap m;
  m.grid = g;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  m.residual.assign(g.size(), nan);
  m.unreachable.assign(g.size(), nan);
  // scallop part of the residual per node: what the pass pairs are judged by.
  std::vector<double> scallop(g.size(), nan);
  UnreachableStats& u = m.unreachable_stats;
  u.computed = reach != nullptr;
  std::size_t on = 0, above = 0;
  double sum = 0;
  for (std::size_t k = 0; k < g.size(); ++k) {
    if (design.off_part[k]) continue;
    const double res = machined[k] - design.z[k];
    m.residual[k] = res;
    const double un = reach ? unreachable_part(machined[k], design.z[k], (*reach)[k]) : 0.0;
    m.unreachable[k] = un;
    scallop[k] = res - un;
    ++on;
    sum += un;
    above += un > kUnreachableMin;
    if (un > u.max) {
      u.max = un;
      const std::size_t column = k % g.nx, row = k / g.nx;
      u.max_x = g.x0 + double(column) * g.dx;
      u.max_y = g.y0 + double(row) * g.dy;
    }
  }
  if (on) {
    u.mean = sum / double(on);
    u.share = double(above) / double(on);
  }
  // Columns run along the passes; "across" indexes the other axis.
  const std::size_t ncol = along_x ? g.nx : g.ny, nacross = along_x ? g.ny : g.nx;
  const double a0 = along_x ? g.y0 : g.x0, da = along_x ? g.dy : g.dx;
  auto node = [&](std::size_t col, std::size_t across) { return along_x ? across * g.nx + col : col * g.nx + across; };
  m.columns = ncol;
  const std::size_t pairs = rows.size() > 1 ? rows.size() - 1 : 0;
  m.pair_scallop.assign(pairs * ncol, std::numeric_limits<double>::quiet_NaN());
  m.strip.assign(g.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t p = 0; p < pairs; ++p) {
    // Nodes strictly between the two passes.
    const double lo = rows[p], hi = rows[p + 1];
    // Only pairs the grid spans entirely: a partial strip would miss the cusp.
    if (lo < a0 - 1e-9 || hi > a0 + double(nacross - 1) * da + 1e-9) continue;
    const double first = std::floor((lo - a0) / da) + 1, last = std::ceil((hi - a0) / da) - 1;
    if (last < 0 || first > double(nacross - 1) || first > last) continue;
    const auto j0 = static_cast<std::size_t>(std::max(0.0, first));
    const auto j1 = static_cast<std::size_t>(std::min(double(nacross - 1), last));
    for (std::size_t c = 0; c < ncol; ++c) {
      double worst = -HUGE_VAL;
      for (std::size_t j = j0; j <= j1; ++j) {
        const double r = scallop[node(c, j)];
        if (std::isfinite(r)) worst = std::max(worst, r);
      }
      if (worst > -HUGE_VAL) m.pair_scallop[p * ncol + c] = std::max(0.0, worst);
      const double v = m.pair_scallop[p * ncol + c];
      for (std::size_t j = j0 > 0 && std::fabs(a0 + double(j0 - 1) * da - lo) < 1e-9 ? j0 - 1 : j0; j <= j1; ++j)
        if (std::isfinite(m.residual[node(c, j)])) m.strip[node(c, j)] = v;
    }
  }
  m.stats = scallop_stats(m.pair_scallop);
  return m;
}

}  // namespace cncstream::cam
