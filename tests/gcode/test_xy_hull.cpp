// The convex hull behind the outline (gcode/xy_hull.hpp), checked against
// its definition on random points, and a program's hull from its moves.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "cncstream/gcode/program_extent.hpp"
#include "cncstream/gcode/xy_hull.hpp"

using namespace cncstream::gcode;

namespace {

double turn(const XyPoint& o, const XyPoint& a, const XyPoint& b) {
  return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

// Signed distance of p inside the counter-clockwise polygon's edges (the
// smallest; negative outside).
double inside_by(const std::vector<XyPoint>& poly, const XyPoint& p) {
  double worst = 1e300;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const XyPoint& a = poly[i];
    const XyPoint& b = poly[(i + 1) % poly.size()];
    worst = std::min(worst, turn(a, b, p) / std::hypot(b[0] - a[0], b[1] - a[1]));
  }
  return worst;
}

}  // namespace

TEST(XyHull, EveryPointInsideEveryVertexAPointAndEveryTurnLeft) {
  std::mt19937 rng(7);
  std::normal_distribution<double> d(0, 20);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<XyPoint> pts(500 + 100 * static_cast<std::size_t>(trial));
    for (auto& p : pts) p = {d(rng), d(rng)};
    HullAccumulator acc(128);  // compacts several times on the way
    for (const auto& p : pts) acc.add(p[0], p[1]);
    const auto h = acc.hull();
    ASSERT_GE(h.size(), 3u);
    EXPECT_EQ(h, convex_hull(pts));
    for (std::size_t i = 0; i < h.size(); ++i) {
      EXPECT_GT(turn(h[i], h[(i + 1) % h.size()], h[(i + 2) % h.size()]), 0) << "not strictly convex at " << i;
      EXPECT_NE(std::find(pts.begin(), pts.end(), h[i]), pts.end());
    }
    for (const auto& p : pts) EXPECT_GE(inside_by(h, p), -1e-9);
  }
  EXPECT_EQ(convex_hull({{0, 0}, {1, 1}, {2, 2}}).size(), 2u);  // a line: no area
  EXPECT_EQ(convex_hull({{0, 0}, {2, 0}, {1, 0}, {1, 1}, {0, 0}}).size(), 3u);
}

TEST(XyHull, SimplifiedHullKeepsItsCornersAndStaysWithinTheTolerance) {
  // A rounded rectangle: 4 arcs of 400 chords each.
  std::vector<XyPoint> pts;
  const double r = 5;
  const XyPoint centres[4] = {{45, 25}, {5, 25}, {5, 5}, {45, 5}};
  for (int q = 0; q < 4; ++q)
    for (int k = 0; k <= 400; ++k) {
      const double a = (q + k / 400.0) * M_PI / 2;
      pts.push_back({centres[q][0] + r * std::cos(a), centres[q][1] + r * std::sin(a)});
    }
  const auto hull = convex_hull(pts);
  const auto s = simplify_hull(hull, 0.1);
  EXPECT_GT(hull.size(), 1000u);
  EXPECT_LT(s.size(), 60u);
  EXPECT_GE(s.size(), 8u);
  for (const auto& p : pts) EXPECT_GE(inside_by(s, p), -0.1 - 1e-9);
  // The straight sides are traced along their length: an edge on X50 spans
  // at least the straight 20 mm.
  double longest_on_x50 = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const XyPoint& a = s[i];
    const XyPoint& b = s[(i + 1) % s.size()];
    if (std::fabs(a[0] - 50) < 0.1 && std::fabs(b[0] - 50) < 0.1)
      longest_on_x50 = std::max(longest_on_x50, std::fabs(b[1] - a[1]));
  }
  EXPECT_GE(longest_on_x50, 20);
  // A square keeps its 4 corners however finely its sides are sampled
  // (each side bowed out by 0.05 mm, so the hull keeps every sample).
  std::vector<XyPoint> square;
  for (int side = 0; side < 4; ++side)
    for (int k = 0; k < 100; ++k) {
      const double u = k * 0.1, bow = 0.05 * std::sin(M_PI * k / 100.0);
      const XyPoint p = side == 0 ? XyPoint{u, -bow}
                        : side == 1 ? XyPoint{10 + bow, u}
                        : side == 2 ? XyPoint{10 - u, 10 + bow}
                                    : XyPoint{-bow, 10 - u};
      square.push_back(p);
    }
  const auto square_hull = convex_hull(square);
  EXPECT_GT(square_hull.size(), 300u);
  const auto four = simplify_hull(square_hull, 0.1);
  ASSERT_EQ(four.size(), 4u);
  for (const XyPoint& c : {XyPoint{0, 0}, XyPoint{10, 0}, XyPoint{10, 10}, XyPoint{0, 10}})
    EXPECT_NE(std::find(four.begin(), four.end(), c), four.end());
}

TEST(XyHull, AProgramsHullFollowsItsArcsAndLeavesOutMachineTargets) {
  const auto e = program_extent({"G21 G90", "G0 Z5", "G0 X0 Y0", "G1 Z-1 F300", "G1 X40", "G3 X40 Y20 I0 J10",
                                 "G1 X0 Y20", "G1 X0 Y0", "G0 Z5", "G53 G0 X-300 Y-300", "M2"});
  ASSERT_GE(e.xy_hull.size(), 6u);
  for (const auto& p : e.xy_hull) {
    EXPECT_GE(p[0], -1e-9);
    EXPECT_LE(p[0], 50 + 1e-9);
  }
  // The arc's bulge to X50 is on it.
  EXPECT_NEAR(std::max_element(e.xy_hull.begin(), e.xy_hull.end())->at(0), 50, 0.01);
  EXPECT_TRUE(program_extent({"G90 G0 X0 Y0", "G1 X10 Y0 F100"}).xy_hull.size() < 3);
}
