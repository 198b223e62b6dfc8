// The pieces of Z-level roughing: the grown cutter, the levels, the stock's
// depth per move, parameter checks.
#include <gtest/gtest.h>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/stock.hpp"
#include "cncstream/cam/zlevel_roughing.hpp"
#include "zlevel_sim.hpp"

using namespace cncstream;

TEST(GrownCutter, GrowsEveryShapeByTheLeave) {
  const cam::Cutter b = cam::grown_cutter(cam::Cutter::ball(6), 0.5);
  EXPECT_EQ(b.type, cam::CutterType::Ball);
  EXPECT_DOUBLE_EQ(b.radius, 3.5);
  EXPECT_DOUBLE_EQ(b.corner_radius, 3.5);
  const cam::Cutter f = cam::grown_cutter(cam::Cutter::flat(6), 0.5);
  EXPECT_EQ(f.type, cam::CutterType::Bull);
  EXPECT_DOUBLE_EQ(f.radius, 3.5);
  EXPECT_DOUBLE_EQ(f.corner_radius, 0.5);
  const cam::Cutter u = cam::grown_cutter(cam::Cutter::bull(6, 1), 0.5);
  EXPECT_DOUBLE_EQ(u.radius, 3.5);
  EXPECT_DOUBLE_EQ(u.corner_radius, 1.5);
  EXPECT_EQ(cam::grown_cutter(cam::Cutter::flat(6), 0).spec(), "flat:6");
  EXPECT_THROW(cam::grown_cutter(cam::Cutter::flat(6), -0.1), std::invalid_argument);
}

TEST(GrownCutter, ItsProfileIsTheCutterOffsetByTheLeave) {
  // Over a flat floor at 0 the grown cutter's tip is at 0; the cutter's tip
  // at leave; along the profile the grown one is the offset of the original.
  const cam::Cutter c = cam::Cutter::bull(6, 1), g = cam::grown_cutter(c, 0.4);
  for (double rho = 0; rho <= 3; rho += 0.1) {
    // The point of the original profile at rho, pushed out along its normal
    // by 0.4, lies on the grown profile (tip 0.4 lower).
    const double rc = c.core_radius();
    double nx = 0, nz = -1;
    if (rho > rc) {
      const double u = rho - rc, w = std::sqrt(1 - u * u);
      nx = u, nz = -w;  // unit normal of the corner circle (radius 1)
    }
    const double px = rho + 0.4 * nx, pz = c.profile_height(rho) + 0.4 + 0.4 * nz;
    EXPECT_NEAR(g.profile_height(px), pz, 1e-9) << rho;
  }
}

TEST(StockDepth, LastMaxDepthIsTheLargestDropOfTheMove) {
  cam::HeightFieldStock s(cam::GridSpec::covering(-10, -10, 10, 10, 0.1, 0.1), 0);
  s.cut_segment({-5, 0, -1}, {5, 0, -1}, cam::Cutter::flat(4));
  EXPECT_DOUBLE_EQ(s.last_max_depth(), 1.0);
  s.cut_segment({-5, 0, -1.5}, {5, 0, -1.5}, cam::Cutter::flat(4));
  EXPECT_DOUBLE_EQ(s.last_max_depth(), 0.5);
  s.cut_segment({-5, 0, 2}, {5, 0, 2}, cam::Cutter::flat(4));
  EXPECT_DOUBLE_EQ(s.last_max_depth(), 0.0);
}

TEST(ZLevelLevels, EveryStepDownTheBottomAndTheFlats) {
  cam::RoughingParams p;
  p.step_down = 3;
  p.tolerance = 0.05;
  std::vector<double> tips = {1.0, 5.0, 5.005, 7.2};
  std::vector<double> flats(40, 5.0);
  flats.push_back(5.005);
  flats.push_back(7.2);  // too small an area for a level
  const cam::LevelPlan plan = cam::plan_levels(tips, flats, 0.25, 12, p, 5.0);
  const std::vector<double> want = {9, 6, 5.005, 3, 1};
  ASSERT_EQ(plan.z.size(), want.size());
  for (std::size_t k = 0; k < want.size(); ++k) EXPECT_DOUBLE_EQ(plan.z[k], want[k]);
  EXPECT_TRUE(plan.flat[2]);
  EXPECT_FALSE(plan.flat[0]);
  p.flat_levels = false;
  EXPECT_EQ(cam::plan_levels(tips, flats, 0.25, 12, p, 5.0).z.size(), 4u);
  p.bottom = 4;
  EXPECT_DOUBLE_EQ(cam::plan_levels(tips, flats, 0.25, 12, p, 5.0).z.back(), 4.0);
  // Nothing below the stock top: no levels.
  EXPECT_TRUE(cam::plan_levels({13.0}, {}, 0.25, 12, p, 5.0).z.empty());
}

TEST(ZLevelRoughing, RejectsBadInput) {
  const geometry::Mesh m = zlevel_test::pocket_block();
  const cam::Cutter c = cam::Cutter::flat(6);
  const cam::ClEngine grown(m, cam::grown_cutter(c, 0.3));
  const cam::StockBlock block{-30, -25, 30, 25, 20};
  cam::RoughingParams p;
  p.leave = 0.3;
  EXPECT_NO_THROW(cam::build_zlevel_roughing(grown, c, block, p));
  cam::RoughingParams bad = p;
  bad.leave = 0.5;  // the engine's cutter is grown by 0.3
  EXPECT_THROW(cam::build_zlevel_roughing(grown, c, block, bad), std::invalid_argument);
  bad = p;
  bad.step_down = 0;
  EXPECT_THROW(cam::build_zlevel_roughing(grown, c, block, bad), std::invalid_argument);
  bad = p;
  bad.ramp_angle_deg = 90;
  EXPECT_THROW(cam::build_zlevel_roughing(grown, c, block, bad), std::invalid_argument);
  EXPECT_THROW(cam::build_zlevel_roughing(grown, c, cam::StockBlock{0, 0, 0, 5, 20}, p), std::invalid_argument);
}

TEST(ZLevelRoughing, ClimbAndOrderSetTheLoopDirections) {
  const geometry::Mesh m = zlevel_test::pocket_block();
  const cam::Cutter c = cam::Cutter::flat(6);
  const cam::ClEngine grown(m, cam::grown_cutter(c, 0.3));
  const cam::StockBlock block{-30, -25, 30, 25, 20};
  cam::RoughingParams p;
  p.leave = 0.3;
  // The last loop of a level is the pocket's boundary: counter-clockwise
  // (material on the right) when climb milling, clockwise otherwise.
  for (const bool climb : {true, false}) {
    p.climb = climb;
    const cam::RoughingPath path = cam::build_zlevel_roughing(grown, c, block, p);
    const cam::Polyline& pts = path.levels.front().passes.front().points;
    // The boundary: the last loop's points (about a rectangle's worth).
    cam::Polyline tail(pts.end() - 5, pts.end());
    double turn = 0;
    for (std::size_t k = 1; k + 1 < tail.size(); ++k) {
      const geometry::Vec3 a = tail[k] - tail[k - 1], b = tail[k + 1] - tail[k];
      turn += a.x * b.y - a.y * b.x;
    }
    EXPECT_EQ(turn > 0, climb);
  }
}
