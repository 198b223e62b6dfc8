// Known-answer cuts on a height-field stock.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "cncstream/cam/stock.hpp"

using namespace cncstream;

namespace {

cam::GridSpec square(double half, double step) { return cam::GridSpec::covering(-half, -half, half, half, step, step); }

std::size_t nearest(double v, double v0, double step) { return static_cast<std::size_t>(std::lround((v - v0) / step)); }

}  // namespace

TEST(StockCuts, BallGrooveCrossSectionIsTheCircle) {
  cam::HeightFieldStock s(square(10, 0.05), 0.0);
  const auto c = cam::Cutter::ball(6);
  s.cut_segment({-8, 0, -2}, {8, 0, -2}, c);
  const auto& g = s.grid();
  const std::size_t i = nearest(0, g.x0, g.dx);
  for (std::size_t j = 0; j < g.ny; ++j) {
    const double y = g.y(j);
    const double circle = std::fabs(y) < 3 ? -2 + 3 - std::sqrt(9 - y * y) : HUGE_VAL;
    EXPECT_NEAR(s.at(i, j), std::min(0.0, circle), 1e-9) << "y=" << y;
  }
  // Beyond the ends only the end half-spheres cut.
  EXPECT_NEAR(s.at(nearest(9, g.x0, g.dx), nearest(0, g.y0, g.dy)), -2 + 3 - std::sqrt(9 - 1.0), 1e-9);
  EXPECT_DOUBLE_EQ(s.at(nearest(-9.5, g.x0, g.dx), nearest(2.9, g.y0, g.dy)), 0.0);
}

TEST(StockCuts, FlatPocketHasFlatBottomAndWallsAtTheRadius) {
  cam::HeightFieldStock s(square(14, 0.05), 0.0);
  const auto c = cam::Cutter::flat(6);
  // Zigzag over the tip rectangle [-7, 7]^2 at depth 3, stepover 2 mm.
  double y = -7;
  bool right = true;
  geometry::Vec3 p{-7, -7, 5};
  s.cut_segment(p, {-7, -7, -3}, c);
  p = {-7, -7, -3};
  while (y <= 7 + 1e-9) {
    const geometry::Vec3 q{right ? 7.0 : -7.0, y, -3};
    s.cut_segment(p, q, c);
    p = q;
    if (y + 2 <= 7 + 1e-9) {
      s.cut_segment(p, {p.x, y + 2, -3}, c);
      p.y = y + 2;
    }
    y += 2;
    right = !right;
  }
  // Finishing contour around the tip rectangle.
  for (const geometry::Vec3& q : {geometry::Vec3{-7, 7, -3}, geometry::Vec3{-7, -7, -3}, geometry::Vec3{7, -7, -3}, geometry::Vec3{7, 7, -3}, geometry::Vec3{-7, 7, -3}}) {
    s.cut_segment(p, q, c);
    p = q;
  }
  const auto& g = s.grid();
  for (std::size_t j = 0; j < g.ny; ++j)
    for (std::size_t i = 0; i < g.nx; ++i) {
      const double x = g.x(i), yy = g.y(j);
      // Distance from the tip rectangle [-7, 7]^2.
      const double ox = std::max(0.0, std::fabs(x) - 7), oy = std::max(0.0, std::fabs(yy) - 7);
      const double d = std::hypot(ox, oy);
      if (d <= 3 - 1e-9) {
        ASSERT_DOUBLE_EQ(s.at(i, j), -3.0) << x << "," << yy;
      }
      if (d > 3 + 1e-9) {
        ASSERT_DOUBLE_EQ(s.at(i, j), 0.0) << x << "," << yy;
      }
    }
  // The wall: x = 9.95 is inside, 10.05 outside.
  const std::size_t j0 = nearest(0, g.y0, g.dy);
  EXPECT_DOUBLE_EQ(s.at(nearest(9.95, g.x0, g.dx), j0), -3.0);
  EXPECT_DOUBLE_EQ(s.at(nearest(10.05, g.x0, g.dx), j0), 0.0);
}

TEST(StockCuts, PlungeLeavesTheCutterShape) {
  for (const cam::Cutter& c : {cam::Cutter::ball(6), cam::Cutter::flat(6), cam::Cutter::bull(6, 1)}) {
    SCOPED_TRACE(c.spec());
    cam::HeightFieldStock s(square(5, 0.1), 0.0);
    const double v = s.cut_segment({0, 0, 5}, {0, 0, -2}, c);
    EXPECT_GT(v, 0);
    EXPECT_GT(s.nodes_cut(), 0u);
    const auto& g = s.grid();
    for (std::size_t j = 0; j < g.ny; ++j)
      for (std::size_t i = 0; i < g.nx; ++i) {
        const double d = std::hypot(g.x(i), g.y(j));
        const double want = d <= 3 ? std::min(0.0, -2 + c.profile_height(d)) : 0.0;
        ASSERT_NEAR(s.at(i, j), want, 1e-12) << g.x(i) << "," << g.y(j);
      }
    // Pulling straight out again removes nothing.
    EXPECT_EQ(s.cut_segment({0, 0, -2}, {0, 0, 5}, c), 0.0);
    EXPECT_EQ(s.nodes_cut(), 0u);
  }
}

TEST(StockCuts, RampFollowsTheOffsetLine) {
  // Tip from (-10, 0, 0) down to (10, 0, -4): slope m = -0.2 per mm.
  const double m = -0.2;
  auto tip_z = [&](double x) { return (x + 10) * m; };
  {
    cam::HeightFieldStock s(square(14, 0.1), 1.0);
    s.cut_segment({-10, 0, 0}, {10, 0, -4}, cam::Cutter::ball(6));
    const auto& g = s.grid();
    const std::size_t j = nearest(0, g.y0, g.dy);
    // A ball's lower envelope along a ramp is the tip line lowered by
    // R (sqrt(1 + m^2) - 1): the sphere touches perpendicular to the path.
    for (double x = -6; x <= 6; x += 0.5)
      EXPECT_NEAR(s.at(nearest(x, g.x0, g.dx), j), tip_z(x) + 3 - 3 * std::sqrt(1 + m * m), 1e-9) << x;
  }
  {
    cam::HeightFieldStock s(square(14, 0.1), 1.0);
    s.cut_segment({-10, 0, 0}, {10, 0, -4}, cam::Cutter::flat(6));
    const auto& g = s.grid();
    const std::size_t j = nearest(0, g.y0, g.dy);
    // A flat end's lowest point over x is its rim R ahead, further down.
    for (double x = -6; x <= 6; x += 0.5)
      EXPECT_NEAR(s.at(nearest(x, g.x0, g.dx), j), tip_z(x + 3), 1e-9) << x;
    // Past the end of the ramp the flat bottom at the final depth.
    EXPECT_NEAR(s.at(nearest(12, g.x0, g.dx), j), -4, 1e-9);
  }
}

TEST(StockCuts, BullGrooveHasFlatBottomOfCoreWidth) {
  cam::HeightFieldStock s(square(8, 0.05), 0.0);
  const auto c = cam::Cutter::bull(6, 1);  // rc = 2
  s.cut_segment({-6, 0, -2}, {6, 0, -2}, c);
  const auto& g = s.grid();
  const std::size_t i = nearest(0, g.x0, g.dx);
  for (std::size_t j = 0; j < g.ny; ++j) {
    const double y = std::fabs(g.y(j));
    if (y <= 2 + 1e-9) {
      EXPECT_DOUBLE_EQ(s.at(i, j), -2) << y;
    } else if (y < 3 + 1e-9) {
      const double u = std::min(y - 2, 1.0);
      EXPECT_NEAR(s.at(i, j), std::min(0.0, -2 + 1 - std::sqrt(1 - u * u)), 1e-9) << y;
      EXPECT_GT(s.at(i, j), -2) << y;
    } else {
      EXPECT_DOUBLE_EQ(s.at(i, j), 0) << y;
    }
  }
}

TEST(StockCuts, ArcOfShortSegmentsCutsTheTorusGroove) {
  cam::HeightFieldStock s(cam::GridSpec::covering(-2, -2, 13, 13, 0.05, 0.05), 0.0);
  const auto c = cam::Cutter::ball(3);
  const double r = 10;
  const int n = 200;
  for (int k = 0; k < n; ++k) {
    const double t0 = std::numbers::pi / 2 * k / n, t1 = std::numbers::pi / 2 * (k + 1) / n;
    s.cut_segment({r * std::cos(t0), r * std::sin(t0), -1}, {r * std::cos(t1), r * std::sin(t1), -1}, c);
  }
  const auto& g = s.grid();
  int checked = 0;
  for (std::size_t j = 0; j < g.ny; ++j)
    for (std::size_t i = 0; i < g.nx; ++i) {
      const double x = g.x(i), y = g.y(j);
      const double ang = std::atan2(y, x);
      if (ang < 0.2 || ang > std::numbers::pi / 2 - 0.2) continue;
      const double d = std::fabs(std::hypot(x, y) - r);
      if (d > 1.0) continue;
      // Chords sag 8e-5 mm below the arc; the profile's slope is < 1 here.
      EXPECT_NEAR(s.at(i, j), -1 + c.profile_height(d), 2e-4) << x << "," << y;
      ++checked;
    }
  EXPECT_GT(checked, 1000);
}

TEST(StockCuts, CuttingTwiceChangesNothing) {
  cam::HeightFieldStock s(square(10, 0.1), 0.0);
  const cam::Cutter cs[] = {cam::Cutter::ball(3.175), cam::Cutter::bull(6, 1), cam::Cutter::flat(4)};
  const geometry::Vec3 path[] = {{-8, -8, 2}, {-8, -8, -1}, {5, -6, -1.5}, {6, 4, -0.5}, {-7, 5, -2.5}, {-3, -2, 1}};
  for (const auto& c : cs)
    for (std::size_t k = 0; k + 1 < std::size(path); ++k) s.cut_segment(path[k], path[k + 1], c);
  const auto before = s.heights();
  for (const auto& c : cs)
    for (std::size_t k = 0; k + 1 < std::size(path); ++k) {
      EXPECT_EQ(s.cut_segment(path[k], path[k + 1], c), 0.0);
      EXPECT_EQ(s.nodes_cut(), 0u);
    }
  EXPECT_EQ(s.heights(), before);
}

TEST(StockCuts, GrooveVolumeMatchesClosedForm) {
  cam::HeightFieldStock s(cam::GridSpec::covering(-5, -5, 25, 5, 0.04, 0.04), 0.0);
  const double R = 3, depth = 2, len = 20;
  const double v = s.cut_segment({0, 0, -depth}, {len, 0, -depth}, cam::Cutter::ball(2 * R));
  // Circular segment of height `depth` times the length, plus the two end
  // half-caps, which make one spherical cap.
  const double seg = R * R * std::acos((R - depth) / R) - (R - depth) * std::sqrt(2 * R * depth - depth * depth);
  const double cap = std::numbers::pi * depth * depth * (3 * R - depth) / 3;
  EXPECT_NEAR(v, seg * len + cap, 0.002 * (seg * len + cap));
  EXPECT_DOUBLE_EQ(s.removed_volume(), v);
}

TEST(StockCuts, OnlyTheFootprintIsVisited) {
  // A diagonal move: nodes further than R from the segment stay untouched
  // even when the cutter is far below them.
  cam::HeightFieldStock s(square(10, 0.1), 0.0);
  s.cut_segment({-5, -4, -50}, {6, 3, -50}, cam::Cutter::flat(4));
  const auto& g = s.grid();
  for (std::size_t j = 0; j < g.ny; ++j)
    for (std::size_t i = 0; i < g.nx; ++i) {
      const double px = g.x(i) + 5, py = g.y(j) + 4, ux = 11, uy = 7, L2 = ux * ux + uy * uy;
      const double t = std::clamp((px * ux + py * uy) / L2, 0.0, 1.0);
      const double d = std::hypot(px - t * ux, py - t * uy);
      if (d < 2 - 1e-9) {
        ASSERT_EQ(s.at(i, j), -50);
      }
      if (d > 2 + 1e-9) {
        ASSERT_EQ(s.at(i, j), 0);
      }
    }
}

TEST(StockCuts, RejectsBadStock) {
  EXPECT_THROW(cam::HeightFieldStock(cam::GridSpec{}, 0), std::invalid_argument);
  cam::GridSpec g = square(1, 0.5);
  EXPECT_THROW(cam::HeightFieldStock(g, NAN), std::invalid_argument);
  cam::HeightFieldStock s(g, 0);
  EXPECT_THROW(s.cut_segment({0, 0, 0}, {INFINITY, 0, 0}, cam::Cutter::ball(1)), std::invalid_argument);
}
