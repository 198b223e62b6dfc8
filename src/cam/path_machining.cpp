#include "cncstream/cam/path_machining.hpp"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "cncstream/cam/stock.hpp"

namespace cncstream::cam {

namespace {

// Rows per band: enough that a band's share of the moves is worth a task,
// few enough that bands balance across cores. Any split gives the same
// heights (bands keep the whole grid's node coordinates).
constexpr std::size_t kBandRows = 32;

}  // namespace

std::vector<Polyline> raster_pieces(const RasterPath& path) {
  std::vector<Polyline> out;
  for (std::size_t r = 0; r < path.rows.size(); ++r) {
    out.push_back(path.rows[r]);
    if (r < path.links.size()) out.push_back(path.links[r]);
  }
  return out;
}

namespace {

std::vector<double> machine(const GridSpec& grid, std::vector<double> heights, const std::vector<Polyline>& pieces,
                            const Cutter& cutter, std::vector<MoveCut>* cuts, const Checkpoint& checkpoint) {
  if (heights.size() != grid.size()) throw std::invalid_argument("machine_path: heights do not match the grid");
  if (grid.size() == 0) return heights;
  double top = -HUGE_VAL;
  for (double z : heights) top = std::max(top, z);
  // The moves in order, as segments.
  struct Move {
    geometry::Vec3 a, b;
  };
  std::vector<Move> moves;
  const geometry::Vec3* last = nullptr;
  for (const auto& pl : pieces)
    for (const auto& p : pl) {
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw std::invalid_argument("machine_path: a point of the path is not finite");
      if (last && !(p.x == last->x && p.y == last->y && p.z == last->z)) moves.push_back({*last, p});
      last = &p;
    }
  // Each band takes, in cutting order, the moves whose cutter can reach its
  // rows (one row of margin); moves above the stock cut nothing.
  const std::size_t bands = (grid.ny + kBandRows - 1) / kBandRows;
  const double R = cutter.radius;
  std::vector<std::vector<std::size_t>> band_moves(bands);
  for (std::size_t k = 0; k < moves.size(); ++k) {
    const Move& m = moves[k];
    if (std::min(m.a.z, m.b.z) >= top) continue;
    const double lo = (std::min(m.a.y, m.b.y) - R - grid.y0) / grid.dy - 1;
    const double hi = (std::max(m.a.y, m.b.y) + R - grid.y0) / grid.dy + 1;
    if (hi < 0 || lo > double(grid.ny - 1)) continue;
    const std::size_t b0 = lo <= 0 ? 0 : std::size_t(lo) / kBandRows;
    const std::size_t b1 = std::min(bands - 1, std::size_t(std::min(hi, double(grid.ny - 1))) / kBandRows);
    for (std::size_t b = b0; b <= b1; ++b) band_moves[b].push_back(k);
  }
  // Per band, the depth of each of its moves that cut (merged after).
  std::vector<std::vector<std::pair<std::size_t, double>>> band_depths(cuts ? bands : 0);
  std::atomic<std::size_t> done{0};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, bands, 1), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t b = r.begin(); b != r.end(); ++b) {
      const std::size_t j0 = b * kBandRows, j1 = std::min(grid.ny, j0 + kBandRows);
      const auto first = heights.begin() + static_cast<std::ptrdiff_t>(j0 * grid.nx);
      const auto end = heights.begin() + static_cast<std::ptrdiff_t>(j1 * grid.nx);
      HeightFieldStock stock = HeightFieldStock::band(grid, j0, top, std::vector<double>(first, end));
      for (std::size_t k : band_moves[b]) {
        stock.cut_segment(moves[k].a, moves[k].b, cutter);
        if (cuts && stock.nodes_cut() > 0) band_depths[b].emplace_back(k, stock.last_max_depth());
      }
      std::copy(stock.heights().begin(), stock.heights().end(), first);
      if (checkpoint) checkpoint(double(++done) / double(bands));
    }
  });
  if (cuts) {
    std::vector<double> depth(moves.size(), -1.0);
    for (const auto& bd : band_depths)
      for (const auto& [k, d] : bd) depth[k] = std::max(depth[k], d);
    for (std::size_t k = 0; k < moves.size(); ++k)
      if (depth[k] >= 0) cuts->push_back({moves[k].a, moves[k].b, depth[k]});
  }
  return heights;
}

}  // namespace

std::vector<double> machine_path(const GridSpec& grid, std::vector<double> heights, const std::vector<Polyline>& pieces,
                                 const Cutter& cutter, const Checkpoint& checkpoint) {
  return machine(grid, std::move(heights), pieces, cutter, nullptr, checkpoint);
}

std::vector<double> machine_path(const GridSpec& grid, std::vector<double> heights, const std::vector<Polyline>& pieces,
                                 const Cutter& cutter, std::vector<MoveCut>& cuts, const Checkpoint& checkpoint) {
  return machine(grid, std::move(heights), pieces, cutter, &cuts, checkpoint);
}

}  // namespace cncstream::cam
