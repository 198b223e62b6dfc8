// The pieces of rest roughing: a roughing path as the tool moves, a pass's
// depth of cut against a stock (its rim left out, bounded after a further
// roughing), and a roughing kept to a window around given points with a
// level that brings the stock there within reach of their heights.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/pass_depth.hpp"
#include "cncstream/cam/path_machining.hpp"
#include "cncstream/cam/stock.hpp"
#include "cncstream/cam/zlevel_roughing.hpp"
#include "zlevel_sim.hpp"

using namespace cncstream;

namespace {

double xy_distance(const geometry::Vec3& a, const geometry::Vec3& b) { return std::hypot(a.x - b.x, a.y - b.y); }

}  // namespace

TEST(RoughingMoves, CutIntoAStockAsTheMachineRunsThePath) {
  const geometry::Mesh mesh = zlevel_test::pocket_block();
  const cam::Cutter cutter = cam::Cutter::flat(6);
  const cam::ClEngine grown(mesh, cam::grown_cutter(cutter, 0.3));
  cam::RoughingParams p;
  p.step_down = 3;
  p.leave = 0.3;
  const cam::RoughingPath path = cam::build_zlevel_roughing(grown, cutter, cam::StockBlock{-30, -25, 30, 25, 20}, p);
  const cam::GridSpec g = cam::GridSpec::covering(-30.11, -25.07, 30, 25, 0.25, 0.25);
  const cam::Polyline moves = cam::roughing_moves(path);
  ASSERT_FALSE(moves.empty());
  EXPECT_DOUBLE_EQ(moves.front().z, path.clearance_z);
  EXPECT_DOUBLE_EQ(moves.back().z, path.clearance_z);
  cam::HeightFieldStock by_move(g, 20);
  (void)zlevel_test::machine(by_move, path);
  const std::vector<double> cut = cam::machine_path(g, std::vector<double>(g.size(), 20.0), {moves}, cutter);
  ASSERT_EQ(cut.size(), by_move.heights().size());
  for (std::size_t n = 0; n < cut.size(); ++n) ASSERT_EQ(cut[n], by_move.heights()[n]) << n;
}

TEST(PassDepth, EachMoveAgainstTheStockItMeets) {
  const cam::GridSpec g = cam::GridSpec::covering(-10, -10, 10, 10, 0.1, 0.1);
  const cam::HeightFieldStock flat(g, 0, std::vector<double>(g.size(), 0.0));
  const cam::Cutter ball = cam::Cutter::ball(3);
  // Two rows 1 mm apart at 1 mm deep: the first takes 1 mm, the second
  // the same depth at its far side; a third 2 mm deep is too deep for 1.5,
  // and so is the plunge to its start.
  const std::vector<cam::Polyline> pieces = {{{-5, 0, -1}, {5, 0, -1}}, {{5, 1, -1}, {-5, 1, -1}}, {{-5, -3, -2}, {5, -3, -2}}};
  const cam::PassDepth d = cam::pass_depth(flat, pieces, ball, 0, 1.5, 5);
  EXPECT_NEAR(d.deepest, 2.0, 1e-9);
  EXPECT_NEAR(d.at.z, -2.0, 1e-12);
  EXPECT_NEAR(d.deepest_within, 1.0, 1e-9);
  ASSERT_EQ(d.too_deep.size(), 2u);
  EXPECT_DOUBLE_EQ(d.too_deep[0].a.z, 5.0);  // the plunge
  EXPECT_DOUBLE_EQ(d.too_deep[1].a.y, -3.0);
  // Along the move, at most a third of the radius apart, at its depth.
  ASSERT_GE(d.over.size(), 21u);
  for (const geometry::Vec3& v : d.over) {
    EXPECT_DOUBLE_EQ(v.y, -3.0);
    EXPECT_DOUBLE_EQ(v.z, -2.0);
  }
  // The moves over between pieces cut nothing: each piece alone as deep.
  EXPECT_NEAR(cam::pass_depth(flat, {pieces[0]}, ball, 0, 1.5, 5).deepest, 1.0, 1e-9);
  EXPECT_NEAR(cam::pass_depth(flat, {pieces[2]}, ball, 0, 1.5, 5).deepest, 2.0, 1e-9);
}

TEST(PassDepth, LeavesOutTheSkinBesideAWallOnTheCuttersRim) {
  // A floor at -1 and a wall at 5 from x = 1.3 on: the ball (R 1.5) moving
  // at -1 along x = 0 takes the wall's first 0.2 mm with its side.
  const cam::GridSpec g = cam::GridSpec::covering(-5, -5, 5, 5, 0.05, 0.05);
  std::vector<double> z(g.size());
  for (std::size_t n = 0; n < z.size(); ++n) z[n] = g.x(n % g.nx) >= 1.3 ? 5.0 : -1.0;
  const cam::HeightFieldStock stock(g, 5, z);
  const std::vector<cam::Polyline> pass = {{{0, -3, -1}, {0, 3, -1}}};
  EXPECT_GT(cam::pass_depth(stock, pass, cam::Cutter::ball(3), 0, 1.5, 6).deepest, 5.0);
  EXPECT_LE(cam::pass_depth(stock, pass, cam::Cutter::ball(3), 0.3, 1.5, 6).deepest, 1e-9);
  EXPECT_THROW(cam::pass_depth(stock, pass, cam::Cutter::ball(3), 1.5, 1.5, 6), std::invalid_argument);
}

TEST(PassDepth, BoundAfterAFurtherCutIsNoLessThanTheDepthMeasured) {
  const cam::GridSpec g = cam::GridSpec::covering(-10, -10, 10, 10, 0.1, 0.1);
  const cam::HeightFieldStock top(g, 0, std::vector<double>(g.size(), 0.0));
  const cam::Cutter ball = cam::Cutter::ball(3);
  const std::vector<cam::Polyline> pieces = {{{-5, 0, -2}, {5, 0, -2}}, {{5, 0.5, -2}, {-5, 0.5, -2}}};
  const cam::PassDepth before = cam::pass_depth(top, pieces, ball, 0, 1.5, 5);
  ASSERT_GE(before.too_deep.size(), 2u);  // the plunges and the rows
  // Lowered by 1 mm under the first row only.
  std::vector<double> z = top.heights();
  for (std::size_t n = 0; n < z.size(); ++n)
    if (std::fabs(g.y(n / g.nx)) < 3) z[n] = -1;
  const cam::HeightFieldStock lower(g, 0, z);
  const cam::PassDepth bound = cam::pass_depth_bound(lower, before, ball, 0, 1.5);
  const cam::PassDepth exact = cam::pass_depth(lower, pieces, ball, 0, 1.5, 5);
  EXPECT_GE(bound.deepest, exact.deepest - 1e-12);
  EXPECT_NEAR(bound.deepest, 1.0, 1e-9);
  EXPECT_TRUE(bound.over.empty());
}

TEST(RestRoughing, ClearsOnlyNearItsPointsWithALevelThatReachesTheirHeight) {
  // The pocket block under a stock 10 mm higher, without flat levels: a
  // point on the plateau beside the pocket (its window reaches the pocket's
  // floor) at 17.2 wants the stock there within 3.3 mm; the levels every
  // 3 mm (27, 24, 21, 18 ... 10.3) have none between the plateau's 20.3 and
  // 20.5.
  const geometry::Mesh mesh = zlevel_test::pocket_block();
  const cam::Cutter cutter = cam::Cutter::flat(6);
  const cam::ClEngine grown(mesh, cam::grown_cutter(cutter, 0.3));
  cam::RoughingParams p;
  p.step_down = 3;
  p.leave = 0.3;
  p.tolerance = 0.02;
  p.flat_levels = false;
  const geometry::Vec3 spot{-16.5, 2, 17.2};
  p.near = {spot};
  p.near_radius = 5;
  const cam::StockBlock block{-30, -25, 30, 25, 30};
  const cam::RoughingPath path = cam::build_zlevel_roughing(grown, cutter, block, p);
  ASSERT_FALSE(path.levels.empty());
  EXPECT_LT(path.grid.size(), 24 * 24 / (path.grid.dx * path.grid.dy));  // only around the spot
  bool at = false;
  for (const auto& lv : path.levels) {
    at |= std::fabs(lv.z - 20.5) < 1e-9;
    for (const auto& ps : lv.passes)
      for (std::size_t k = ps.entry_points; k < ps.points.size(); ++k)
        ASSERT_LE(xy_distance(ps.points[k], spot), p.near_radius + (1 + std::sqrt(2.0)) * path.grid.dx + p.tolerance)
            << "level " << lv.z;
  }
  EXPECT_TRUE(at) << "no level at 17.2 + 3 + 0.3";
  EXPECT_NEAR(path.levels.back().z, 10.3, 1e-9);  // the pocket's floor
  // Cut: the stock at the spot within the step down and leave of its height;
  // far from it, untouched.
  const cam::GridSpec g = cam::GridSpec::covering(-30.11, -25.07, 30, 25, 0.25, 0.25);
  cam::HeightFieldStock stock(g, 30);
  const zlevel_test::SimResult sim = zlevel_test::machine(stock, path);
  EXPECT_LE(sim.deepest_cut, 3 + 1e-9);
  EXPECT_LE(sim.rapid_removed, 1e-9);
  const auto i = static_cast<std::size_t>(std::lround((spot.x - g.x0) / g.dx));
  const auto j = static_cast<std::size_t>(std::lround((spot.y - g.y0) / g.dy));
  EXPECT_LE(stock.at(i, j), 20.5 + 1e-9);
  EXPECT_DOUBLE_EQ(stock.at(g.nx - 1, g.ny - 1), 30.0);
  // Points outside the stock: nothing to cut.
  p.near = {{100, 100, 0}};
  EXPECT_TRUE(cam::build_zlevel_roughing(grown, cutter, block, p).levels.empty());
  p.near_radius = 0;
  EXPECT_THROW(cam::build_zlevel_roughing(grown, cutter, block, p), std::invalid_argument);
}
