#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "cncstream/cam/level_band_fit.hpp"

using namespace cncstream;

namespace {

// Points on a circle of radius r about the origin at level z, every `spacing`
// along it, over `sweep` radians from angle a0; clockwise: the inside (the
// part) on the right.
cam::Polyline arc_points(double r, double a0, double sweep, double spacing, bool clockwise, double z = -1) {
  cam::Polyline p;
  const auto n = static_cast<int>(std::ceil(r * sweep / spacing));
  for (int k = 0; k <= n; ++k) {
    const double a = a0 + (clockwise ? -1 : 1) * sweep * double(k) / n;
    p.push_back({r * std::cos(a), r * std::sin(a), z});
  }
  return p;
}

// Signed distance of q from the move a -> b: positive left of it.
double side_of(const geometry::Vec3& a, const geometry::Vec3& b, const geometry::Vec3& q) {
  return ((b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x)) / std::hypot(b.x - a.x, b.y - a.y);
}

// Every point of the run lies right of the fitted path, within tol of it:
// measured from the nearest move it projects onto.
void expect_right_within(const cam::Polyline& run, const cam::Polyline& fit, double tol) {
  for (const geometry::Vec3& q : run) {
    double best = HUGE_VAL, side = 0;
    for (std::size_t m = 0; m + 1 < fit.size(); ++m) {
      const geometry::Vec3 &a = fit[m], &b = fit[m + 1];
      const double len = std::hypot(b.x - a.x, b.y - a.y);
      const double t = std::clamp(((q.x - a.x) * (b.x - a.x) + (q.y - a.y) * (b.y - a.y)) / (len * len), 0.0, 1.0);
      const double d = std::hypot(q.x - (a.x + t * (b.x - a.x)), q.y - (a.y + t * (b.y - a.y)));
      if (d < best) best = d, side = side_of(a, b, q);
    }
    EXPECT_LE(best, tol + 1e-9) << q.x << "," << q.y;
    EXPECT_LE(side, 1e-9) << "left of the path (the part cut into) at " << q.x << "," << q.y;
  }
}

}  // namespace

TEST(FitLevelRunInBand, OutsideCornerIsCircumscribedWithMovesOfSqrt8RT) {
  // Round a part's outside corner the contour is a circle about it with the
  // part on the right: every chord between its points cuts in, so a subset
  // of them cannot merge; vertices out to T away take sqrt(8 R T).
  for (const double tol : {0.002, 0.005}) {
    const double r = 1.6;
    const cam::Polyline run = arc_points(r, std::numbers::pi, std::numbers::pi, 0.005, true);
    const cam::Polyline fit = cam::fit_level_run_in_band(run, tol);
    ASSERT_GE(fit.size(), 3u);
    EXPECT_EQ(fit.front().x, run.front().x);
    EXPECT_EQ(fit.back().y, run.back().y);
    expect_right_within(run, fit, tol);
    for (const geometry::Vec3& v : fit) {
      EXPECT_EQ(v.z, -1);
      const double d = std::hypot(v.x, v.y);
      EXPECT_GE(d, r - 1e-9);
      EXPECT_LE(d, r + tol + 1e-9);
    }
    std::vector<double> lengths;
    // Inner moves: those by the kept ends start on the circle, not out from it.
    for (std::size_t m = 2; m + 3 < fit.size(); ++m) lengths.push_back(cam::xy_dist(fit[m], fit[m + 1]));
    std::sort(lengths.begin(), lengths.end());
    const double expected = std::sqrt(8 * r * tol);
    EXPECT_NEAR(lengths[lengths.size() / 2], expected, 0.1 * expected) << tol;
    EXPECT_GT(lengths.front(), 0.8 * expected) << tol;
  }
}

TEST(FitLevelRunInBand, InsideCornerChordsStayOnTheFreeSide) {
  // Counter-clockwise round a circle with the part on the right: the part
  // is outside the circle, chords between points pass on the free side.
  const double tol = 0.005, r = 2.0;
  const cam::Polyline run = arc_points(r, 0, std::numbers::pi / 2, 0.01, false);
  const cam::Polyline fit = cam::fit_level_run_in_band(run, tol);
  expect_right_within(run, fit, tol);
  const double expected = std::sqrt(8 * r * tol);
  EXPECT_LE(fit.size(), std::size_t(r * std::numbers::pi / 2 / (0.8 * expected)) + 2);
}

TEST(FitLevelRunInBand, LiftedPointsAndLevelChangesAreKept) {
  cam::Polyline run = arc_points(1.6, std::numbers::pi, 1.0, 0.005, true);
  const std::size_t mid = run.size() / 2;
  run[mid].z = -0.5;  // lifted over the part
  const cam::Polyline fit = cam::fit_level_run_in_band(run, 0.005);
  EXPECT_NE(std::find_if(fit.begin(), fit.end(), [&](const geometry::Vec3& v) { return v.x == run[mid].x && v.y == run[mid].y && v.z == -0.5; }), fit.end());
  // Either side of it: the level stretches' ends, exactly.
  EXPECT_NE(std::find_if(fit.begin(), fit.end(), [&](const geometry::Vec3& v) { return v.x == run[mid - 1].x && v.y == run[mid - 1].y; }), fit.end());
  EXPECT_NE(std::find_if(fit.begin(), fit.end(), [&](const geometry::Vec3& v) { return v.x == run[mid + 1].x && v.y == run[mid + 1].y; }), fit.end());
  const cam::Polyline before(run.begin(), run.begin() + std::ptrdiff_t(mid));
  expect_right_within(before, cam::Polyline(fit.begin(), std::find_if(fit.begin(), fit.end(), [](const geometry::Vec3& v) { return v.z != -1; })), 0.005);
}

TEST(FitLevelRunInBand, VerticesOnTheLatticeWhereTheBandAllows) {
  const cam::XYLattice lat{0.001, 0.0003, -0.0007};
  const double tol = 0.005;
  const cam::Polyline run = arc_points(1.6, std::numbers::pi, std::numbers::pi, 0.005, true);
  const cam::Polyline fit = cam::fit_level_run_in_band(run, tol, lat);
  expect_right_within(run, fit, tol);
  std::size_t on = 0;
  for (std::size_t m = 1; m + 1 < fit.size(); ++m) {
    const double i = (fit[m].x - lat.x0) / lat.step, j = (fit[m].y - lat.y0) / lat.step;
    on += std::fabs(i - std::round(i)) < 1e-6 && std::fabs(j - std::round(j)) < 1e-6;
  }
  EXPECT_EQ(on, fit.size() - 2);
}
