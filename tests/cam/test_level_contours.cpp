// Level contours: known shapes, orientation, refinement and nesting.
#include <gtest/gtest.h>

#include <cmath>

#include "cncstream/cam/distance_transform.hpp"
#include "cncstream/cam/level_contours.hpp"

using namespace cncstream;

namespace {

std::vector<double> sample(const cam::GridSpec& g, const cam::PointQuery& f) {
  std::vector<double> v(g.size());
  for (std::size_t j = 0; j < g.ny; ++j)
    for (std::size_t i = 0; i < g.nx; ++i) v[j * g.nx + i] = f(g.x(i), g.y(j));
  return v;
}

const cam::GridSpec kGrid = cam::GridSpec::covering(-5, -5, 5, 5, 0.5, 0.5);

}  // namespace

TEST(LevelContours, ConeGivesOneCounterClockwiseCircle) {
  const cam::PointQuery cone = [](double x, double y) { return std::hypot(x - 0.1, y + 0.2); };
  cam::ContourOptions o;
  o.xy_tolerance = 1e-5;
  o.z_tolerance = 1e-5;
  o.sharp_corners = false;  // the circle's own points only
  for (const bool refined : {false, true}) {
    const cam::LevelContours c = cam::level_contours(kGrid, sample(kGrid, cone), 3.0, refined ? cone : cam::PointQuery{}, o);
    ASSERT_EQ(c.contours.size(), 1u);
    const cam::LevelContour& loop = c.contours.front();
    EXPECT_TRUE(loop.closed);
    EXPECT_GT(cam::signed_area2(loop.points), 0);  // the disc on the left
    EXPECT_GT(loop.points.size(), 20u);
    for (const geometry::Vec3& p : loop.points) {
      const double r = cone(p.x, p.y);
      EXPECT_NEAR(r, 3.0, refined ? 1e-5 : 0.02);
      if (refined) {
        EXPECT_LE(r, 3.0);  // refined crossings lie inside
      }
      EXPECT_DOUBLE_EQ(p.z, 3.0);
    }
    EXPECT_EQ(c.queries > 0, refined);
    EXPECT_NEAR(std::fabs(cam::signed_area2(loop.points)) / 2, 3.14159265 * 9, 0.2);
  }
}

TEST(LevelContours, HoleIsClockwise) {
  const cam::PointQuery well = [](double x, double y) { return -std::hypot(x, y); };
  const cam::LevelContours c = cam::level_contours(kGrid, sample(kGrid, well), -2.0, well);
  ASSERT_EQ(c.contours.size(), 1u);
  EXPECT_TRUE(c.contours[0].closed);
  EXPECT_LT(cam::signed_area2(c.contours[0].points), 0);
}

TEST(LevelContours, RegionThroughTheBorderGivesAnOpenChainWithTheRegionOnTheLeft) {
  const cam::PointQuery ramp = [](double x, double) { return x; };
  const cam::LevelContours c = cam::level_contours(kGrid, sample(kGrid, ramp), 0.3);
  ASSERT_EQ(c.contours.size(), 1u);
  const cam::Polyline& p = c.contours[0].points;
  EXPECT_FALSE(c.contours[0].closed);
  ASSERT_EQ(p.size(), kGrid.ny);
  // x <= 0.3 on the left: the chain runs towards +y.
  EXPECT_DOUBLE_EQ(p.front().y, kGrid.y0);
  EXPECT_DOUBLE_EQ(p.back().y, kGrid.y1());
  for (const geometry::Vec3& v : p) EXPECT_NEAR(v.x, 0.3, 1e-12);
}

TEST(LevelContours, StepIsRefinedToTheInsideWithinTheTolerance) {
  const cam::PointQuery wall = [](double x, double y) { return x < 1.2345 + 0.1 * std::sin(y) ? 0.0 : 10.0; };
  for (const bool nested : {false, true}) {
    cam::ContourOptions o;
    o.xy_tolerance = 1e-3;
    o.nested = nested;
    o.sharp_corners = false;
    const cam::LevelContours c = cam::level_contours(kGrid, sample(kGrid, wall), 5.0, wall, o);
    ASSERT_EQ(c.contours.size(), 1u);
    for (const geometry::Vec3& v : c.contours[0].points) {
      const double edge = 1.2345 + 0.1 * std::sin(v.y);
      if (std::fabs(v.y - std::round(v.y * 2) / 2) > 1e-12) continue;  // on a vertical cell edge
      EXPECT_LT(v.x, edge);
      EXPECT_GT(v.x, edge - 1e-3);
    }
  }
}

TEST(LevelContours, NestedRefinementGivesTheSameWallAtEveryLevel) {
  // A vertical wall: every level between the two sides has the same region.
  const cam::PointQuery wall = [](double x, double y) { return x < 1.2345 + 0.3 * std::sin(y) ? 0.0 : 10.0; };
  cam::ContourOptions o;
  o.nested = true;
  const auto v = sample(kGrid, wall);
  const cam::LevelContours a = cam::level_contours(kGrid, v, 2.0, wall, o), b = cam::level_contours(kGrid, v, 7.0, wall, o);
  ASSERT_EQ(a.contours.size(), 1u);
  ASSERT_EQ(b.contours.size(), 1u);
  EXPECT_EQ(a.contours[0].points.size(), b.contours[0].points.size());
  for (std::size_t k = 0; k < a.contours[0].points.size(); ++k) {
    EXPECT_DOUBLE_EQ(a.contours[0].points[k].x, b.contours[0].points[k].x);
    EXPECT_DOUBLE_EQ(a.contours[0].points[k].y, b.contours[0].points[k].y);
  }
}

TEST(LevelContours, SharpCornerOfASquareIsRecovered) {
  const double h = 2.2345;  // corners off the grid
  const cam::PointQuery square = [h](double x, double y) { return std::max(std::fabs(x), std::fabs(y)) <= h ? 0.0 : 1.0; };
  cam::ContourOptions o;
  o.xy_tolerance = 1e-4;
  const cam::LevelContours c = cam::level_contours(kGrid, sample(kGrid, square), 0.5, square, o);
  ASSERT_EQ(c.contours.size(), 1u);
  EXPECT_EQ(c.corner_points.size(), 4u);
  for (const double sx : {-1.0, 1.0})
    for (const double sy : {-1.0, 1.0}) {
      double best = 1e9;
      for (const geometry::Vec3& p : c.contours[0].points) best = std::min(best, std::hypot(p.x - sx * h, p.y - sy * h));
      EXPECT_LT(best, 1e-3) << sx << "," << sy;
    }
  for (const geometry::Vec3& p : c.contours[0].points) EXPECT_LE(std::max(std::fabs(p.x), std::fabs(p.y)), h);
}

TEST(LevelContours, SaddleFollowsTheCellMean) {
  const cam::GridSpec g = cam::GridSpec::covering(0, 0, 1, 1, 1, 1);
  // a and c (diagonal) inside, mean 5.
  const std::vector<double> v = {0, 10, 10, 0};  // (0,0) (1,0) / (0,1) (1,1)
  const cam::LevelContours joined = cam::level_contours(g, v, 5.0), split = cam::level_contours(g, v, 4.9);
  ASSERT_EQ(joined.contours.size(), 2u);
  ASSERT_EQ(split.contours.size(), 2u);
  // Joined: each chain cuts off an outside corner; split: an inside one.
  auto near_corner = [](const cam::LevelContour& c, double x, double y) {
    const geometry::Vec3 m = (c.points.front() + c.points.back()) * 0.5;
    return std::hypot(m.x - x, m.y - y) < 0.5;
  };
  const bool a_joined = near_corner(joined.contours[0], 1, 0) || near_corner(joined.contours[0], 0, 1);
  const bool a_split = near_corner(split.contours[0], 0, 0) || near_corner(split.contours[0], 1, 1);
  EXPECT_TRUE(a_joined);
  EXPECT_TRUE(a_split);
}

TEST(LevelContours, RejectsBadInput) {
  EXPECT_THROW(cam::level_contours(kGrid, std::vector<double>(3), 0.0), std::invalid_argument);
  EXPECT_THROW(cam::level_contours(cam::GridSpec::covering(0, 0, 1, 0, 1, 1), std::vector<double>(2), 0.0),
               std::invalid_argument);
}

TEST(DistanceTransform, DistancesToTheNearestOutsideNode) {
  const cam::GridSpec g = cam::GridSpec::covering(0, 0, 10, 10, 0.5, 0.5);
  std::vector<std::uint8_t> in(g.size(), 1);
  in[4 * g.nx + 6] = 0;  // one outside node at (3, 2)
  const std::vector<double> d = cam::distance_to_outside(g, in);
  EXPECT_DOUBLE_EQ(d[4 * g.nx + 6], 0.0);
  EXPECT_DOUBLE_EQ(d[4 * g.nx + 8], 1.0);                  // (4, 2)
  EXPECT_NEAR(d[8 * g.nx + 10], std::hypot(2.0, 2.0), 1e-12);  // (5, 4)
  // Beyond the border counts as outside: (10, 3) is half a cell from it.
  EXPECT_DOUBLE_EQ(d[6 * g.nx + 20], 0.5);
  EXPECT_THROW(cam::distance_to_outside(g, std::vector<std::uint8_t>(2)), std::invalid_argument);
}

TEST(DistanceTransform, BeyondTheBorderCanBeInside) {
  const cam::GridSpec g = cam::GridSpec::covering(0, 0, 10, 10, 0.5, 0.5);
  std::vector<std::uint8_t> in(g.size(), 1);
  in[4 * g.nx + 6] = 0;  // (3, 2)
  const std::vector<double> d = cam::distance_to_outside(g, in, false);
  EXPECT_NEAR(d[6 * g.nx + 20], std::hypot(7.0, 1.0), 1e-12);  // (10, 3): only the node counts
  EXPECT_DOUBLE_EQ(d[4 * g.nx + 6], 0.0);
  const std::vector<double> none = cam::distance_to_outside(g, std::vector<std::uint8_t>(g.size(), 1), false);
  EXPECT_TRUE(std::isinf(none[0]));
}
