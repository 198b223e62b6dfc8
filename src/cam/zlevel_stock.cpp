// The height-map stock of Z-level roughing; see zlevel_stock.hpp.
#include "zlevel_stock.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "cncstream/cam/distance_transform.hpp"
#include "cncstream/cam/stock.hpp"

namespace cncstream::cam::detail {

std::vector<double> stock_top_on_grid(const GridSpec& g, const StockBlock& s) {
  constexpr double none = std::numeric_limits<double>::lowest();  // no stock
  std::vector<double> top(g.size(), none);
  const HeightFieldStock* surf = s.surface;
  for (std::size_t j = 0; j < g.ny; ++j)
    for (std::size_t i = 0; i < g.nx; ++i) {
      // The window of one cell around the node, clipped to the block.
      const double x0 = std::max(g.x(i) - g.dx, s.x0), x1 = std::min(g.x(i) + g.dx, s.x1);
      const double y0 = std::max(g.y(j) - g.dy, s.y0), y1 = std::min(g.y(j) + g.dy, s.y1);
      if (x0 > x1 || y0 > y1) continue;
      if (!surf) {
        top[j * g.nx + i] = s.top;
        continue;
      }
      const GridSpec& sg = surf->grid();
      // The window reaches beyond the surface's nodes: the block's top there.
      const bool covered = x0 >= sg.x0 - sg.dx && x1 <= sg.x1() + sg.dx && y0 >= sg.y0 - sg.dy && y1 <= sg.y1() + sg.dy;
      double h = covered ? none : s.top;
      const long i0 = std::max(0L, static_cast<long>(std::floor((x0 - sg.x0) / sg.dx)));
      const long i1 = std::min(static_cast<long>(sg.nx) - 1, static_cast<long>(std::ceil((x1 - sg.x0) / sg.dx)));
      const long j0 = std::max(0L, static_cast<long>(std::floor((y0 - sg.y0) / sg.dy)));
      const long j1 = std::min(static_cast<long>(sg.ny) - 1, static_cast<long>(std::ceil((y1 - sg.y0) / sg.dy)));
      for (long jj = j0; jj <= j1; ++jj)
        for (long ii = i0; ii <= i1; ++ii)
          h = std::max(h, surf->at(static_cast<std::size_t>(ii), static_cast<std::size_t>(jj)));
      top[j * g.nx + i] = std::min(h, s.top);
    }
  return top;
}

std::vector<double> material_reach(const GridSpec& g, const std::vector<double>& top, double z, double above,
                                   double reach) {
  std::vector<std::uint8_t> empty(g.size());
  for (std::size_t n = 0; n < g.size(); ++n) empty[n] = top[n] > z + above ? 0 : 1;
  std::vector<double> d = distance_to_outside(g, empty, false);  // beyond the grid: no stock
  for (double& v : d) v -= reach;
  return d;
}

double interpolate(const GridSpec& g, const std::vector<double>& v, double x, double y) {
  const double fx = std::clamp((x - g.x0) / g.dx, 0.0, static_cast<double>(g.nx - 1));
  const double fy = std::clamp((y - g.y0) / g.dy, 0.0, static_cast<double>(g.ny - 1));
  const auto i = std::min(static_cast<std::size_t>(fx), g.nx - 2), j = std::min(static_cast<std::size_t>(fy), g.ny - 2);
  const double tx = fx - static_cast<double>(i), ty = fy - static_cast<double>(j);
  const double* r0 = v.data() + j * g.nx + i;
  const double* r1 = r0 + g.nx;
  return (r0[0] * (1 - tx) + r0[1] * tx) * (1 - ty) + (r1[0] * (1 - tx) + r1[1] * tx) * ty;
}

}  // namespace cncstream::cam::detail
