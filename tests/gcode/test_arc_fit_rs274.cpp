// LinuxCNC's rs274 on fitted arcs in all three planes, both ways round: it
// accepts the program (its own radius check included) and makes the same
// moves of it as our interpreter: same ends, centres, planes and turns
// (G18's sense included, which both take from +Y).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "cncstream/gcode/arc_fit.hpp"
#include "cncstream/gcode/gcode_writer.hpp"
#include "support/rs274.hpp"

using namespace cncstream;
using gcode::Plane;

namespace {

// Points on a circle in `plane` ((first, second) as G2/G3 measure them), at
// the program's 3 decimals.
std::vector<geometry::Vec3> circle(Plane plane, geometry::Vec3 start_shift, double r, double from_deg, double to_deg) {
  std::vector<geometry::Vec3> pts;
  const int n = 40;
  for (int k = 0; k <= n; ++k) {
    const double a = (from_deg + (to_deg - from_deg) * k / n) * std::numbers::pi / 180;
    const double u = r * std::cos(a), v = r * std::sin(a);
    geometry::Vec3 p = plane == Plane::XY ? geometry::Vec3{u, v, 0} : plane == Plane::ZX ? geometry::Vec3{v, 0, u} : geometry::Vec3{0, u, v};
    p = p + start_shift;
    pts.push_back({std::round(p.x * 1e3) / 1e3, std::round(p.y * 1e3) / 1e3, std::round(p.z * 1e3) / 1e3});
  }
  return pts;
}

}  // namespace

TEST(ArcFitRs274, LinuxCncAgreesInAllThreePlanes) {
  if (!test::rs274_available()) GTEST_SKIP() << "rs274 (Debian package linuxcnc-uspace) is not installed";
  GcodeWriter w(3);
  w.line("G21 G90 G17 G94");
  w.rapid(0, 0, 5);
  ArcFitOptions o;
  o.tolerance = 0.01;
  int arcs = 0;
  geometry::Vec3 at{0, 0, 5};
  const Plane planes[] = {Plane::XY, Plane::ZX, Plane::YZ};
  for (int k = 0; k < 6; ++k) {
    const Plane plane = planes[k % 3];
    const bool reverse = k >= 3;
    std::vector<geometry::Vec3> pts = circle(plane, at + geometry::Vec3{1, 2, 3}, 12.5 + k, reverse ? 160 : 20, reverse ? 20 : 160);
    w.feed(pts[0].x, pts[0].y, pts[0].z, 400);
    for (const FittedMove& m : fit_arcs(pts, o)) {
      if (!m.arc) {
        w.feed(m.to.x, m.to.y, m.to.z, 400);
        continue;
      }
      ++arcs;
      EXPECT_EQ(m.plane, plane);
      EXPECT_EQ(m.clockwise, reverse);
      const int g = m.plane == Plane::XY ? 17 : m.plane == Plane::ZX ? 18 : 19;
      w.arc(g, m.clockwise, m.to.x, m.to.y, m.to.z, m.center_offset.x, m.center_offset.y, m.center_offset.z, 400);
    }
    at = pts.back();
  }
  w.line("M2");
  EXPECT_EQ(arcs, 6);

  std::string error;
  const auto ours = test::our_moves(w.text(), error);
  EXPECT_EQ(error, "");
  const auto theirs = test::run_rs274(w.text());
  EXPECT_EQ(theirs.status, 0) << theirs.output;
  EXPECT_EQ(theirs.output.find("rror"), std::string::npos) << theirs.output;
  EXPECT_EQ(theirs.output.find("differs"), std::string::npos) << theirs.output;
  ASSERT_EQ(ours.size(), theirs.moves.size());
  int arcs_seen = 0;
  for (std::size_t k = 0; k < ours.size(); ++k) {
    SCOPED_TRACE(k);
    const auto& a = ours[k];
    const auto& b = theirs.moves[k];
    EXPECT_EQ(a.arc, b.arc);
    EXPECT_EQ(a.rapid, b.rapid);
    EXPECT_LT(norm(a.to - b.to), 1e-4);  // rs274 prints 4 decimals
    if (a.arc && b.arc) {
      ++arcs_seen;
      EXPECT_EQ(a.plane, b.plane);
      EXPECT_EQ(a.turn, b.turn);
      EXPECT_LT(norm(a.centre - b.centre), 1e-4);
    }
  }
  EXPECT_EQ(arcs_seen, 6);
}

// A program of fitted raster profiles over material (G18 and G19 rows with
// convex and concave stretches) runs through rs274 without a complaint.
TEST(ArcFitRs274, RasterProfilesAreAccepted) {
  if (!test::rs274_available()) GTEST_SKIP() << "rs274 (Debian package linuxcnc-uspace) is not installed";
  GcodeWriter w(3);
  w.line("G21 G90 G17 G94");
  ArcFitOptions o;
  o.tolerance = 0.01;
  o.material_below = true;
  int arcs = 0;
  for (int row = 0; row < 4; ++row) {
    std::vector<geometry::Vec3> pts;
    for (int k = 0; k <= 400; ++k) {
      const double s = k * 0.05;
      const double z = std::ceil((-3 + 2 * std::sin(0.3 * s + row) + 0.5 * std::cos(0.9 * s)) * 1000 - 1e-6) / 1000;
      pts.push_back(row % 2 == 0 ? geometry::Vec3{s, 0.4 * row, z} : geometry::Vec3{0.4 * row, s, z});
    }
    w.rapid(std::nullopt, std::nullopt, 5);
    w.rapid(pts[0].x, pts[0].y, std::nullopt);
    w.feed(pts[0].x, pts[0].y, pts[0].z, 400);
    for (const FittedMove& m : fit_arcs(pts, o)) {
      if (!m.arc) {
        w.feed(m.to.x, m.to.y, m.to.z, 400);
        continue;
      }
      ++arcs;
      const int g = m.plane == Plane::XY ? 17 : m.plane == Plane::ZX ? 18 : 19;
      w.arc(g, m.clockwise, m.to.x, m.to.y, m.to.z, m.center_offset.x, m.center_offset.y, m.center_offset.z, 400);
    }
  }
  w.line("M2");
  EXPECT_GT(arcs, 20);
  std::string error;
  const auto ours = test::our_moves(w.text(), error);
  EXPECT_EQ(error, "");
  const auto theirs = test::run_rs274(w.text());
  EXPECT_EQ(theirs.status, 0) << theirs.output;
  ASSERT_EQ(ours.size(), theirs.moves.size());
  for (std::size_t k = 0; k < ours.size(); ++k) {
    EXPECT_LT(norm(ours[k].to - theirs.moves[k].to), 1e-4) << k;
    EXPECT_EQ(ours[k].turn, theirs.moves[k].turn) << k;
    if (ours[k].arc) {
      EXPECT_LT(norm(ours[k].centre - theirs.moves[k].centre), 1e-4) << k;
    }
  }
}
