// Z-level roughing machined in the simulator from the stock block: no move
// cuts into the stock to leave, none cuts deeper than the step down, moves
// over and descents cut nothing, and what is left above the part grown by
// the stock to leave is within the terrace bound wherever the cutter reaches.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <algorithm>
#include <cmath>
#include <limits>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/stock.hpp"
#include "cncstream/cam/zlevel_roughing.hpp"
#include "cncstream/geometry/stl.hpp"
#include "zlevel_sim.hpp"

using namespace cncstream;

namespace {

struct Case {
  const char* mesh;      // relative to the source tree or the shared meshes
  bool shared;
  const char* cutter;
  double step_down;
  double sim_step;
  cam::ClearingOrder order = cam::ClearingOrder::InsideOut;
  bool climb = true;
  double scale = 1;
};

void rough_and_check(const Case& k) {
  const auto file = k.shared ? std::filesystem::path(CNCSTREAM_SHARED_MESHES) / k.mesh
                             : std::filesystem::path(CNCSTREAM_SOURCE_DIR) / k.mesh;
  geometry::Mesh mesh = geometry::load_stl(file).mesh;
  for (geometry::Vec3& v : mesh.vertices) v = v * k.scale;
  const cam::Cutter cutter = cam::parse_cutter_spec(k.cutter);
  cam::RoughingParams p;
  p.step_down = k.step_down;
  p.leave = 0.3;
  p.tolerance = 0.05;
  p.order = k.order;
  p.climb = k.climb;
  const geometry::Box3 box = mesh.bounds();
  const cam::StockBlock block{box.lo.x, box.lo.y, box.hi.x, box.hi.y, box.hi.z + 1};
  const cam::ClEngine grown(mesh, cam::grown_cutter(cutter, p.leave));
  const auto t0 = std::chrono::steady_clock::now();
  const cam::RoughingPath path = cam::build_zlevel_roughing(grown, cutter, block, p);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_FALSE(path.levels.empty());
  std::size_t points = 0;
  for (const auto& lv : path.levels)
    for (const auto& ps : lv.passes) points += ps.points.size();
  std::printf("[ roughing ] %s %s step %g: %.3f s, %zu levels, %zu passes, %zu points, terrace bound %.3f mm\n", k.mesh,
              k.cutter, k.step_down, secs, path.levels.size(), path.stats.passes, points, path.terrace_bound);

  // Stock nodes off round numbers, so none sits exactly on a wall.
  const cam::GridSpec g = cam::GridSpec::covering(block.x0 + 0.0373, block.y0 + 0.0411, block.x1, block.y1, k.sim_step, k.sim_step);
  cam::HeightFieldStock stock(g, block.top);
  const zlevel_test::SimResult sim = zlevel_test::machine(stock, path);
  EXPECT_LE(sim.rapid_removed, 1e-9) << "a move over or a descent cut material";  // rounding only
  EXPECT_LE(sim.deepest_cut, p.step_down + 1e-6);

  // The stock to leave: nowhere closer to the part than leave - tolerance
  // (the top of the part grown by a ball of that radius).
  const double least = p.leave - p.tolerance;
  const cam::ClEngine probe(mesh, cam::Cutter::ball(2 * least));
  const cam::ClGrid offset = probe.compute(g);
  // The reach: the cutter's lowest surface with its tip anywhere allowed.
  const std::size_t pad = static_cast<std::size_t>(std::ceil(cutter.radius / g.dx)) + 1;
  cam::GridSpec tg = g;
  tg.x0 -= static_cast<double>(pad) * g.dx, tg.y0 -= static_cast<double>(pad) * g.dy;
  tg.nx += 2 * pad, tg.ny += 2 * pad;
  const cam::ClGrid cl = grown.compute(tg);
  std::vector<double> tips(tg.size());
  for (std::size_t n = 0; n < tg.size(); ++n) {
    const double x = tg.x(n % tg.nx), y = tg.y(n / tg.nx);
    const double ex = std::max({0.0, block.x0 - x, x - block.x1}), ey = std::max({0.0, block.y0 - y, y - block.y1});
    const bool in_box = std::hypot(ex, ey) <= cutter.radius;
    tips[n] = in_box ? cl.z[n] + p.leave : std::numeric_limits<double>::infinity();
  }
  // The regions are found on a grid: a part of one narrower than a cell
  // (the far end of a bay between gear teeth) can be missed. The reach
  // counts a tip only where the tip may go down as far all round within a
  // cell of the roughing grid.
  std::vector<double> robust(tips.size(), std::numeric_limits<double>::infinity());
  const double cell = path.grid.dx;
  const long rc = static_cast<long>(std::ceil(cell / g.dx));
  for (std::size_t j = 0; j < tg.ny; ++j)
    for (std::size_t i = 0; i < tg.nx; ++i) {
      double worst = -std::numeric_limits<double>::infinity();
      for (long dj = -rc; dj <= rc; ++dj)
        for (long di = -rc; di <= rc; ++di) {
          const long ii = static_cast<long>(i) + di, jj = static_cast<long>(j) + dj;
          if (std::hypot(static_cast<double>(di) * g.dx, static_cast<double>(dj) * g.dy) > cell) continue;
          if (ii < 0 || jj < 0 || ii >= static_cast<long>(tg.nx) || jj >= static_cast<long>(tg.ny)) {
            worst = std::numeric_limits<double>::infinity();
            continue;
          }
          worst = std::max(worst, tips[static_cast<std::size_t>(jj) * tg.nx + static_cast<std::size_t>(ii)]);
        }
      robust[j * tg.nx + i] = worst;
    }
  const std::vector<double> ideal = zlevel_test::ideal_surface(g, pad, robust, cutter, block.top);

  std::size_t into_leave = 0, too_much = 0;
  double worst_in = 0, worst_over = 0;
  for (std::size_t n = 0; n < g.size(); ++n) {
    const double m = stock.heights()[n];
    const double below = (offset.z[n] + least) - m;  // > 0: into the stock to leave
    if (below > 1e-6) ++into_leave;
    worst_in = std::max(worst_in, below);
    const double over = m - ideal[n];
    if (over > path.terrace_bound + p.tolerance && ++too_much <= 5)
      ADD_FAILURE() << "left " << over << " mm above the reach at " << g.x(n % g.nx) << ", " << g.y(n / g.nx);
    worst_over = std::max(worst_over, over);
  }
  EXPECT_EQ(into_leave, 0u) << "deepest into the stock to leave: " << worst_in << " mm";
  EXPECT_EQ(too_much, 0u) << "most left above the reach: " << worst_over << " mm, bound " << path.terrace_bound;
  std::printf("[ roughing ] deepest cut %.4f mm, into the leave %.4f mm, most above the reach %.4f mm\n",
              sim.deepest_cut, worst_in, worst_over);
}

}  // namespace

TEST(ZLevelMachining, PlaqueFlat6) { rough_and_check({"examples/plaque.stl", false, "flat:6", 3, 0.5}); }

TEST(ZLevelMachining, GearwheelFlat3) { rough_and_check({"gearwheel.bin.stl", true, "flat:3", 2, 0.25}); }

TEST(ZLevelMachining, GearwheelFlat3OutsideInConventional) {
  rough_and_check({"gearwheel.bin.stl", true, "flat:3", 2, 0.25, cam::ClearingOrder::OutsideIn, false});
}

// A relief with many levels: found a level's sharp corner poking out of the
// level above's boundary (a 24 mm deep cut) before corners were checked.
TEST(ZLevelMachining, LionReliefFlat6) {
  rough_and_check({"lion_head_relief.stl", true, "flat:6", 3, 0.5, cam::ClearingOrder::InsideOut, true, 100});
}

TEST(ZLevelMachining, PlaqueBull6) { rough_and_check({"examples/plaque.stl", false, "bull:6:1", 3, 0.5}); }
