// Known answer: roughing a rectangular pocket with vertical walls is the
// pocket shrunk by the stock to leave at every level, its floor left at the
// stock to leave.
#include <gtest/gtest.h>

#include <cmath>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/stock.hpp"
#include "cncstream/cam/zlevel_roughing.hpp"
#include "zlevel_sim.hpp"

using namespace cncstream;

namespace {

struct Pocket {
  geometry::Mesh mesh = zlevel_test::pocket_block();
  cam::Cutter cutter = cam::Cutter::flat(6);
  cam::RoughingParams params;
  cam::StockBlock block{-30, -25, 30, 25, 20};
  cam::ClEngine grown{mesh, cam::grown_cutter(cutter, 0.3)};
  cam::RoughingPath path;
  Pocket() {
    params.step_down = 3;
    params.leave = 0.3;
    params.tolerance = 0.02;
    path = cam::build_zlevel_roughing(grown, cutter, block, params);
  }
};

// Tip region at every level: the pocket inset by R + leave.
constexpr double kX = 15 - 3.3, kY = 10 - 3.3;

}  // namespace

TEST(ZLevelPocket, LevelsAreEveryStepDownAndTheFloor) {
  const Pocket k;
  ASSERT_EQ(k.path.levels.size(), 4u);
  const double want[] = {17, 14, 11, 10.3};
  for (std::size_t i = 0; i < 4; ++i) EXPECT_NEAR(k.path.levels[i].z, want[i], 1e-9);
  EXPECT_NEAR(k.path.terrace_bound, 3.0, 1e-9);
}

TEST(ZLevelPocket, EachLevelIsThePocketInOnePass) {
  const Pocket k;
  const double tol = k.params.tolerance;
  double above = k.block.top;
  for (const auto& lv : k.path.levels) {
    ASSERT_EQ(lv.passes.size(), 1u) << "level " << lv.z;
    const cam::RoughingPass& ps = lv.passes.front();
    EXPECT_TRUE(ps.lift_before);
    double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9;
    for (std::size_t n = 0; n < ps.points.size(); ++n) {
      const geometry::Vec3& v = ps.points[n];
      // Never outside the tip region.
      ASSERT_LE(std::fabs(v.x), kX + 1e-9) << v.x << "," << v.y;
      ASSERT_LE(std::fabs(v.y), kY + 1e-9) << v.x << "," << v.y;
      if (n > ps.entry_points) {
        EXPECT_DOUBLE_EQ(v.z, lv.z);
      }
      x0 = std::min(x0, v.x), x1 = std::max(x1, v.x), y0 = std::min(y0, v.y), y1 = std::max(y1, v.y);
    }
    // The last loop is the region's boundary: out to the walls within the tolerance.
    EXPECT_GT(x0, -kX - 1e-9);
    EXPECT_LT(x0, -kX + tol);
    EXPECT_GT(x1, kX - tol);
    EXPECT_LT(y0, -kY + tol);
    EXPECT_GT(y1, kY - tol);
    std::size_t on_wall = 0;
    for (const geometry::Vec3& v : ps.points)
      if (std::min(kX - std::fabs(v.x), kY - std::fabs(v.y)) < tol / 4) ++on_wall;
    EXPECT_GT(on_wall, 4u);
    const geometry::Vec3& last = ps.points.back();
    EXPECT_LT(std::min(kX - std::fabs(last.x), kY - std::fabs(last.y)), tol / 4) << "the boundary is not last";
    // The entry ramps from above the level above, no steeper than the ramp angle.
    ASSERT_GT(ps.entry_points, 0u);
    EXPECT_DOUBLE_EQ(ps.points.front().z, above + 0.5);
    above = lv.z;
    const double slope = std::tan(k.params.ramp_angle_deg * 3.14159265358979 / 180);
    for (std::size_t n = 1; n <= ps.entry_points; ++n) {
      const geometry::Vec3 d = ps.points[n] - ps.points[n - 1];
      EXPECT_LE(-d.z, slope * std::hypot(d.x, d.y) + 1e-9);
    }
  }
}

TEST(ZLevelPocket, MachinedIsThePocketLessTheStockToLeave) {
  const Pocket k;
  const cam::GridSpec g = cam::GridSpec::covering(-29.9627, -24.9589, 30, 25, 0.25, 0.25);
  cam::HeightFieldStock stock(g, 20);
  const zlevel_test::SimResult sim = zlevel_test::machine(stock, k.path);
  EXPECT_LE(sim.rapid_removed, 1e-9);
  EXPECT_LE(sim.deepest_cut, 3 + 1e-9);
  const double leave = 0.3, tol = k.params.tolerance;
  for (std::size_t j = 0; j < g.ny; ++j)
    for (std::size_t i = 0; i < g.nx; ++i) {
      const double x = g.x(i), y = g.y(j), m = stock.at(i, j);
      // Distance inside the pocket wall (negative: outside the pocket).
      const double in = std::min(15 - std::fabs(x), 10 - std::fabs(y));
      if (in < leave - tol) {
        ASSERT_DOUBLE_EQ(m, 20.0) << x << "," << y;
        continue;
      }
      // The flat cutter rounds the pocket's corners by its radius.
      const double cx = std::max(0.0, std::fabs(x) - kX), cy = std::max(0.0, std::fabs(y) - kY);
      if (in > leave + tol && std::hypot(cx, cy) < 3 - tol) {
        ASSERT_NEAR(m, 10.3, 1e-6) << x << "," << y;
      }
      ASSERT_GE(m, 10.3 - 1e-9);
    }
}

// Known answer: around a hemisphere of radius 10 a ball cutter of radius 3
// leaving 0.3 may go down to z where its grown ball (radius 3.3) centred at
// z + 3 touches the sphere: at distance sqrt(13.3^2 - (z + 3)^2) from the axis.
TEST(ZLevelHemisphere, EveryLevelFollowsTheCircleOfItsHeight) {
  const geometry::Mesh dome = cl_test::hemisphere(10, 48, 192);
  const cam::Cutter ball = cam::Cutter::ball(6);
  const cam::ClEngine grown(dome, cam::grown_cutter(ball, 0.3));
  cam::RoughingParams p;
  p.leave = 0.3;
  p.step_down = 3;
  p.tolerance = 0.02;
  p.bottom = 0.3;  // the open hemisphere's rim would let the ball below it
  const cam::RoughingPath path = cam::build_zlevel_roughing(grown, ball, cam::StockBlock{-12, -12, 12, 12, 11}, p);
  // Levels closer than the step down by the ball's scallop between loops.
  ASSERT_GE(path.levels.size(), 5u);
  EXPECT_NEAR(path.terrace_bound, 3.0, 1e-9);
  for (const auto& lv : path.levels) {
    if (lv.z < 1) continue;  // the floor level: everywhere
    const double r = std::sqrt(13.3 * 13.3 - (lv.z + 3) * (lv.z + 3));
    double nearest = 1e9;
    for (const auto& ps : lv.passes)
      for (std::size_t n = ps.entry_points + 1; n < ps.points.size(); ++n) {
        const double d = std::hypot(ps.points[n].x, ps.points[n].y);
        // The facets lie inside the sphere by up to 0.006 mm.
        ASSERT_GE(d, r - 0.01) << "level " << lv.z;
        nearest = std::min(nearest, d);
      }
    EXPECT_LT(nearest, r + p.tolerance) << "level " << lv.z;
  }
}

// A stock already machined: a block of top 26 whose left half is down at 21.
// Levels start at the highest point; above 21 only the right half (and the
// cutter's reach beside it) is cleared; machined, the result is the same
// pocket, no move deeper than the step down.
TEST(ZLevelPocket, MachinedStockIsClearedOnlyWhereMaterialIsAboveTheLevel) {
  const geometry::Mesh mesh = zlevel_test::pocket_block();
  const cam::Cutter cutter = cam::Cutter::flat(6);
  const cam::ClEngine grown(mesh, cam::grown_cutter(cutter, 0.3));
  // The surface covers the block (beyond it: nothing, at 0).
  const cam::GridSpec g = cam::GridSpec::covering(-30.2127, -25.2089, 30.3, 25.3, 0.25, 0.25);
  std::vector<double> before(g.size());
  for (std::size_t n = 0; n < g.size(); ++n) {
    const double x = g.x(n % g.nx), y = g.y(n / g.nx);
    before[n] = std::fabs(x) > 30 || std::fabs(y) > 25 ? 0.0 : x < 0 ? 21.0 : 26.0;
  }
  const cam::HeightFieldStock surface(g, 26, before);
  cam::RoughingParams p;
  p.leave = 0.3;
  p.step_down = 3;
  p.tolerance = 0.02;
  cam::StockBlock block{-30, -25, 30, 25, 30, &surface};  // the block's top is above the surface
  const cam::RoughingPath path = cam::build_zlevel_roughing(grown, cutter, block, p);
  ASSERT_FALSE(path.levels.empty());
  EXPECT_DOUBLE_EQ(path.levels.front().z, 23.0);
  EXPECT_DOUBLE_EQ(path.clearance_z, 26.0 + p.clearance);
  // The stock on the roughing grid reaches a cell (and a surface node)
  // further; the reach is R and two cells.
  const double reach = 3 + 3 * path.grid.dx + g.dx + p.tolerance;
  for (const auto& lv : path.levels) {
    if (lv.z < 21) break;
    for (const auto& ps : lv.passes)
      for (const geometry::Vec3& v : ps.points) ASSERT_GE(v.x, -reach) << "level " << lv.z;
  }
  cam::HeightFieldStock stock(g, 26, before);
  const zlevel_test::SimResult sim = zlevel_test::machine(stock, path);
  EXPECT_LE(sim.rapid_removed, 1e-9);
  EXPECT_LE(sim.deepest_cut, 3 + 1e-9);
  for (std::size_t j = 0; j < g.ny; ++j)
    for (std::size_t i = 0; i < g.nx; ++i) {
      const double x = g.x(i), y = g.y(j), m = stock.at(i, j);
      const double in = std::min(15 - std::fabs(x), 10 - std::fabs(y));
      if (std::fabs(x) > 30 || std::fabs(y) > 25) continue;
      if (in < 0.3 - p.tolerance) {
        ASSERT_NEAR(m, 20.3, 1e-9) << x << "," << y;  // the block's top, less the stock to leave
        continue;
      }
      ASSERT_GE(m, 10.3 - 1e-9);
    }
}
