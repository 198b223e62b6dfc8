#include "cncstream/cam/path_machining.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "cncstream/cam/stock.hpp"

namespace cncstream {

std::vector<Polyline> raster_pieces(const RasterPath& path) {
  std::vector<Polyline> out;
  for (std::size_t r = 0; r < path.rows.size(); ++r) {
    out.push_back(path.rows[r]);
    if (r < path.links.size()) out.push_back(path.links[r]);
  }
  return out;
}

std::vector<double> machine_path(const GridSpec& grid, std::vector<double> heights, const std::vector<Polyline>& pieces,
                                 const Cutter& cutter, unsigned threads) {
  if (heights.size() != grid.size()) throw std::invalid_argument("machine_path: heights do not match the grid");
  if (grid.size() == 0) return heights;
  double top = -HUGE_VAL;
  for (double z : heights) top = std::max(top, z);
  // The moves in order, as segments.
  struct Move {
    Vec3 a, b;
  };
  std::vector<Move> moves;
  const Vec3* last = nullptr;
  for (const auto& pl : pieces)
    for (const auto& p : pl) {
      if (last && !(p.x == last->x && p.y == last->y && p.z == last->z)) moves.push_back({*last, p});
      last = &p;
    }
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  const unsigned workers = std::max(1u, std::min<unsigned>(threads ? threads : hw, static_cast<unsigned>(grid.ny)));
  const double R = cutter.radius;
  std::exception_ptr error;
  std::mutex error_mutex;
  auto band = [&](unsigned w) {
    try {
      const std::size_t j0 = grid.ny * w / workers, j1 = grid.ny * (w + 1) / workers;
      if (j0 >= j1) return;
      GridSpec sub = grid;
      sub.y0 = grid.y(j0);
      sub.ny = j1 - j0;
      std::vector<double> z(heights.begin() + static_cast<std::ptrdiff_t>(j0 * grid.nx),
                            heights.begin() + static_cast<std::ptrdiff_t>(j1 * grid.nx));
      HeightFieldStock stock(sub, top, std::move(z));
      const double ylo = sub.y0 - R - grid.dy, yhi = sub.y1() + R + grid.dy;
      for (const Move& m : moves) {
        if (std::max(m.a.y, m.b.y) < ylo || std::min(m.a.y, m.b.y) > yhi) continue;
        if (std::min(m.a.z, m.b.z) >= top) continue;  // above the stock: cuts nothing
        stock.cut_segment(m.a, m.b, cutter);
      }
      std::copy(stock.heights().begin(), stock.heights().end(), heights.begin() + static_cast<std::ptrdiff_t>(j0 * grid.nx));
    } catch (...) {
      std::lock_guard lock(error_mutex);
      if (!error) error = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  for (unsigned w = 1; w < workers; ++w) pool.emplace_back(band, w);
  band(0);
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
  return heights;
}

}  // namespace cncstream
