// The per-node swept-envelope rule against a brute-force reference that
// samples the tip path densely: the exact minimum must never be above any
// sample, and never far below the best one.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "cncstream/cam/stock.hpp"

using namespace cncstream;

namespace {

double brute_force(const geometry::Vec3& a, const geometry::Vec3& b, const cam::Cutter& c, double x, double y, int n) {
  double best = HUGE_VAL;
  for (int k = 0; k <= n; ++k) {
    const double t = static_cast<double>(k) / n;
    const geometry::Vec3 p = a + (b - a) * t;
    const double d = std::hypot(x - p.x, y - p.y);
    if (d <= c.radius) best = std::min(best, p.z + c.profile_height(d));
  }
  return best;
}

void check_random(const cam::Cutter& c, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-5, 5);
  int reached = 0;
  for (int trial = 0; trial < 400; ++trial) {
    geometry::Vec3 a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)};
    switch (trial % 5) {
      case 0: b.z = a.z; break;                       // level move
      case 1: b.x = a.x, b.y = a.y; break;            // plunge / retract
      case 2: b.z = a.z + 0.05 * (b.z - a.z); break;  // gentle ramp
      default: break;                                 // any direction
    }
    const double x = (a.x + b.x) / 2 + u(rng) * 0.8, y = (a.y + b.y) / 2 + u(rng) * 0.8;
    const double exact = cam::swept_lowest_height(a, b, c, x, y);
    const double ref = brute_force(a, b, c, x, y, 20000);
    SCOPED_TRACE(::testing::Message() << c.spec() << " trial " << trial << " a=(" << a.x << "," << a.y << ","
                                      << a.z << ") b=(" << b.x << "," << b.y << "," << b.z << ") p=(" << x << ","
                                      << y << ")");
    // Reached exactly when the point is within R of the path in XY.
    const double ux = b.x - a.x, uy = b.y - a.y, L2 = ux * ux + uy * uy;
    const double t = L2 > 0 ? std::clamp(((x - a.x) * ux + (y - a.y) * uy) / L2, 0.0, 1.0) : 0.0;
    const double dist = std::hypot(x - a.x - t * ux, y - a.y - t * uy);
    EXPECT_EQ(std::isinf(exact), dist > c.radius) << dist;
    if (std::isinf(ref)) continue;
    ++reached;
    ASSERT_FALSE(std::isinf(exact));
    EXPECT_LE(exact, ref + 1e-9);
    EXPECT_GE(exact, ref - 2e-3);
  }
  EXPECT_GT(reached, 100);
}

}  // namespace

TEST(SweptEnvelope, BallMatchesBruteForce) { check_random(cam::Cutter::ball(6), 1); }
TEST(SweptEnvelope, FlatMatchesBruteForce) { check_random(cam::Cutter::flat(6), 2); }
TEST(SweptEnvelope, BullMatchesBruteForce) { check_random(cam::Cutter::bull(6, 1), 3); }
TEST(SweptEnvelope, SmallCornerBullMatchesBruteForce) { check_random(cam::Cutter::bull(8, 0.25), 4); }

TEST(SweptEnvelope, OutOfReachIsInfinite) {
  const auto c = cam::Cutter::ball(4);
  EXPECT_TRUE(std::isinf(cam::swept_lowest_height({0, 0, 0}, {10, 0, 0}, c, 5, 2.01)));
  EXPECT_TRUE(std::isinf(cam::swept_lowest_height({0, 0, 0}, {10, 0, 0}, c, -2.01, 0)));
  EXPECT_DOUBLE_EQ(cam::swept_lowest_height({0, 0, 0}, {10, 0, 0}, c, 5, 2.0), 2.0);
}

TEST(SweptEnvelope, RejectsBadInput) {
  EXPECT_THROW(cam::swept_lowest_height({0, 0, NAN}, {1, 0, 0}, cam::Cutter::ball(2), 0, 0), std::invalid_argument);
  EXPECT_THROW(cam::swept_lowest_height({0, 0, 0}, {1, 0, 0}, cam::Cutter{cam::CutterType::Ball, 0, 0}, 0, 0),
               std::invalid_argument);
  EXPECT_THROW(cam::swept_lowest_height({0, 0, 0}, {1, 0, 0}, cam::Cutter{cam::CutterType::Bull, 1, 2}, 0, 0),
               std::invalid_argument);
}
