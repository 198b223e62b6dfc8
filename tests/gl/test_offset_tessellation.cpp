// The offset tessellation without GL: the cap's points lie on the exact
// cutter surface, and its triangles stay within [exact - bound, exact] with
// bound <= the tolerance, checked at many points of its shadow.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "cncstream/gl/offset_tessellation.hpp"

using namespace cncstream;
using cncstream::gl::CutterCap;

namespace {

double exact_top(const cam::Cutter& c, double rho) { return -c.profile_height(rho); }

// The cap's height at (x, y) by barycentric interpolation; false outside it.
bool cap_height(const CutterCap& cap, double x, double y, double& z) {
  const auto& P = cap.points();
  for (const auto& t : cap.triangles()) {
    const geometry::Vec3 a = P[t[0]], b = P[t[1]], c = P[t[2]];
    const double det = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    const double l1 = ((x - a.x) * (c.y - a.y) - (y - a.y) * (c.x - a.x)) / det;
    const double l2 = ((b.x - a.x) * (y - a.y) - (b.y - a.y) * (x - a.x)) / det;
    const double l0 = 1 - l1 - l2;
    if (l0 >= -1e-12 && l1 >= -1e-12 && l2 >= -1e-12) {
      z = l0 * a.z + l1 * b.z + l2 * c.z;
      return true;
    }
  }
  return false;
}

}  // namespace

TEST(CutterCap, PointsLieOnTheCutterSurface) {
  for (const cam::Cutter& c : {cam::Cutter::flat(6), cam::Cutter::ball(6), cam::Cutter::bull(6, 1), cam::Cutter::bull(10, 4)}) {
    const CutterCap cap(c, 0.05);
    SCOPED_TRACE(c.spec());
    EXPECT_EQ(cap.spokes() % 4, 0u);
    EXPECT_DOUBLE_EQ(cap.ring_radius().back(), c.radius);
    const auto& rho = cap.ring_radius();
    for (std::size_t k = 0; k < rho.size(); ++k) {
      EXPECT_NEAR(cap.ring_height()[k], exact_top(c, rho[k]), 1e-12);
      for (std::size_t j = 0; j < cap.spokes(); ++j) {
        const geometry::Vec3& p = cap.points()[1 + k * cap.spokes() + j];
        EXPECT_NEAR(std::hypot(p.x, p.y), rho[k], 1e-12);
        EXPECT_EQ(p.z, cap.ring_height()[k]);
      }
    }
  }
}

TEST(CutterCap, WithinTheToleranceBelowTheExactSurfaceAndNeverAbove) {
  std::mt19937 rng(7);
  for (double tol : {0.1, 0.03}) {
    for (const cam::Cutter& c : {cam::Cutter::flat(6), cam::Cutter::ball(6), cam::Cutter::bull(6, 1), cam::Cutter::bull(10, 4)}) {
      SCOPED_TRACE(c.spec() + " tolerance " + std::to_string(tol));
      const CutterCap cap(c, tol);
      EXPECT_LE(cap.height_error_bound(), tol);
      EXPECT_LE(cap.sliver_width(), tol / 20);
      std::uniform_real_distribution<double> u(0, 1);
      double worst = 0;
      int inside = 0;
      for (int k = 0; k < 4000; ++k) {
        // Half the samples in the outer tenth, where the profile is steepest.
        const double rho = c.radius * (k % 2 ? std::sqrt(u(rng)) : 1 - 0.1 * u(rng));
        const double th = 2 * M_PI * u(rng);
        double z = 0;
        if (!cap_height(cap, rho * std::cos(th), rho * std::sin(th), z)) {
          EXPECT_GT(rho, c.radius - cap.sliver_width() - 1e-12);  // only the rim sliver is missing
          continue;
        }
        ++inside;
        const double e = exact_top(c, rho);
        EXPECT_LE(z, e + 1e-12);
        worst = std::max(worst, e - z);
      }
      EXPECT_GT(inside, 3900);
      EXPECT_LE(worst, cap.height_error_bound() + 1e-12);
    }
  }
}

TEST(CutterCap, RejectsABadTolerance) {
  EXPECT_THROW(CutterCap(cam::Cutter::ball(6), 0), std::invalid_argument);
  EXPECT_THROW(CutterCap(cam::Cutter::ball(6), -1), std::invalid_argument);
  EXPECT_THROW(CutterCap(cam::Cutter::ball(6), NAN), std::invalid_argument);
}

TEST(FaceOffset, TheThesisOffsetVectorForTheToolTip) {
  std::array<geometry::Vec3, 3> t;
  // Horizontal facet: the tip sits on it for every cutter.
  for (const cam::Cutter& c : {cam::Cutter::flat(6), cam::Cutter::ball(6), cam::Cutter::bull(6, 1)}) {
    ASSERT_TRUE(gl::face_offset_triangle({0, 0, 5}, {10, 0, 5}, {0, 10, 5}, c, t));
    EXPECT_DOUBLE_EQ(t[0].z, 5);
    EXPECT_DOUBLE_EQ(t[0].x, 0);
  }
  // A 45-degree plane z = x: ball tip at x + R sin45... n = (-1, 0, 1)/sqrt2.
  ASSERT_TRUE(gl::face_offset_triangle({0, 0, 0}, {10, 0, 10}, {0, 10, 0}, cam::Cutter::ball(6), t));
  const double s = std::sqrt(0.5);
  EXPECT_NEAR(t[0].x, -3 * s, 1e-12);
  EXPECT_NEAR(t[0].z, 3 * s - 3, 1e-12);
  // Flat: moved by R horizontally down the slope, z unchanged.
  ASSERT_TRUE(gl::face_offset_triangle({0, 0, 0}, {10, 0, 10}, {0, 10, 0}, cam::Cutter::flat(6), t));
  EXPECT_NEAR(t[0].x, -3, 1e-12);
  EXPECT_NEAR(t[0].z, 0, 1e-12);
  // Vertical facet: no face offset.
  EXPECT_FALSE(gl::face_offset_triangle({0, 0, 0}, {10, 0, 0}, {0, 0, 10}, cam::Cutter::ball(6), t));
}
