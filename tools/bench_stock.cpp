// Material-removal speed: short G1 moves on a 120 x 100 mm stock with a
// 0.1 mm grid, single-threaded, as the simulator issues them.
//   bench_stock --benchmark_filter=. (items_per_second = moves per second)
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <vector>

#include "cncstream/cam/stock.hpp"

using namespace cncstream;

namespace {

constexpr double kW = 120, kH = 100, kStep = 0.1;

cam::GridSpec stock_grid() { return cam::GridSpec::covering(0, 0, kW, kH, kStep, kStep); }

// A raster finishing path over a wavy surface: moves of `seg` mm along x,
// rows `stepover` apart, the tip following z = -3 + 1.5 sin(x/9) cos(y/7).
std::vector<geometry::Vec3> raster_path(double seg, double stepover, bool wavy) {
  std::vector<geometry::Vec3> p;
  bool right = true;
  for (double y = 2; y <= kH - 2; y += stepover) {
    const int n = static_cast<int>((kW - 4) / seg);
    for (int k = 0; k <= n; ++k) {
      const double x = right ? 2 + k * seg : kW - 2 - k * seg;
      const double z = wavy ? -3 + 1.5 * std::sin(x / 9) * std::cos(y / 7) : -1.0;
      p.push_back({x, y, z});
    }
    right = !right;
  }
  return p;
}

void run_path(benchmark::State& state, const std::vector<geometry::Vec3>& path, const cam::Cutter& cutter) {
  auto stock = std::make_unique<cam::HeightFieldStock>(stock_grid(), 0.0);
  std::size_t k = 0;
  double removed = 0;
  for (auto _ : state) {
    if (k + 1 >= path.size()) {
      // A whole pass done: start again on fresh stock so every move cuts.
      state.PauseTiming();
      stock = std::make_unique<cam::HeightFieldStock>(stock_grid(), 0.0);
      k = 0;
      state.ResumeTiming();
    }
    removed += stock->cut_segment(path[k], path[k + 1], cutter);
    ++k;
  }
  benchmark::DoNotOptimize(removed);
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

void BM_BallFinish05(benchmark::State& state) {
  static const auto path = raster_path(0.5, 0.3, true);
  run_path(state, path, cam::Cutter::ball(3.175));
}
void BM_BallFinish02(benchmark::State& state) {
  static const auto path = raster_path(0.2, 0.3, true);
  run_path(state, path, cam::Cutter::ball(3.175));
}
void BM_BallLevel1(benchmark::State& state) {
  static const auto path = raster_path(1.0, 1.0, false);
  run_path(state, path, cam::Cutter::ball(3.175));
}
void BM_BullFinish05(benchmark::State& state) {
  static const auto path = raster_path(0.5, 0.3, true);
  run_path(state, path, cam::Cutter::bull(6, 1));
}
void BM_FlatLevel1(benchmark::State& state) {
  static const auto path = raster_path(1.0, 2.0, false);
  run_path(state, path, cam::Cutter::flat(6));
}

}  // namespace

BENCHMARK(BM_BallFinish05)->MinTime(1.0);
BENCHMARK(BM_BallFinish02)->MinTime(1.0);
BENCHMARK(BM_BallLevel1)->MinTime(1.0);
BENCHMARK(BM_BullFinish05)->MinTime(1.0);
BENCHMARK(BM_FlatLevel1)->MinTime(1.0);
BENCHMARK_MAIN();
