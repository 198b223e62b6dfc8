// Arc fitting: known answers in the three planes, and on random polylines
// every point within the tolerance of the path the controller cuts, that path
// taken from the fitted moves written as G-code, run through our interpreter
// and cut into chords as GRBL does ($12).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "cncstream/gcode/arc_fit.hpp"
#include "cncstream/gcode/arc_segments.hpp"
#include "cncstream/gcode/gcode_writer.hpp"
#include "cncstream/gcode/interpreter.hpp"
#include "cncstream/gcode/line_lexer.hpp"

using namespace cncstream;
using namespace cncstream::gcode;

namespace {

constexpr double kDollar12 = 0.002;

// The moves as G-code lines (G90, mm), written by the program writer.
std::vector<std::string> gcode_of(const std::vector<geometry::Vec3>& pts, const std::vector<FittedMove>& moves) {
  GcodeWriter w(6, 120);
  w.feed(pts[0].x, pts[0].y, pts[0].z, 500);
  for (const FittedMove& m : moves) {
    if (!m.arc) {
      w.feed(m.to.x, m.to.y, m.to.z, 500);
    } else {
      const int plane = m.plane == Plane::XY ? 17 : m.plane == Plane::ZX ? 18 : 19;
      EXPECT_TRUE(w.arc(plane, m.clockwise, m.to.x, m.to.y, m.to.z, m.center_offset.x, m.center_offset.y,
                        m.center_offset.z, 500));
    }
  }
  return w.lines();
}

// The tool-tip path our interpreter makes of the program: every line end and
// every chord end of the arcs at the controller's arc tolerance, from the
// first line's end (the first line moves there from the origin).
std::vector<geometry::Vec3> cut_path(const std::vector<std::string>& lines, double dollar12, int* arcs = nullptr) {
  ParserState s;
  std::vector<geometry::Vec3> path;
  bool first = true;
  for (const std::string& l : lines) {
    const BlockResult r = execute_block(s, clean_line(l).text);
    EXPECT_TRUE(r.ok()) << l << " -> error " << r.status;
    if (!r.ok()) continue;
    for (const Action& a : r.actions) {
      if (const auto* lm = std::get_if<LinearMove>(&a)) {
        if (!first) path.push_back(lm->to);
        else path = {lm->to};
        first = false;
      } else if (const auto* am = std::get_if<ArcMove>(&a)) {
        if (arcs) ++*arcs;
        for (const geometry::Vec3& p : segment_arc(*am, dollar12)) path.push_back(p);
      }
    }
    s = r.state;
  }
  return path;
}

double distance_to_segment(const geometry::Vec3& p, const geometry::Vec3& a, const geometry::Vec3& b) {
  const geometry::Vec3 d = b - a;
  const double l2 = dot(d, d);
  const double t = l2 > 0 ? std::clamp(dot(p - a, d) / l2, 0.0, 1.0) : 0.0;
  return norm(p - (a + d * t));
}

double distance_to_path(const geometry::Vec3& p, const std::vector<geometry::Vec3>& path) {
  double best = HUGE_VAL;
  for (std::size_t k = 0; k + 1 < path.size(); ++k) best = std::min(best, distance_to_segment(p, path[k], path[k + 1]));
  return best;
}

// Points on a circle in `plane`: (first, second) axis coordinates as G2/G3
// measure them, the third coordinate fixed.
std::vector<geometry::Vec3> circle_points(Plane plane, double c0, double c1, double r, double from_deg, double to_deg,
                                double step_deg, double fixed) {
  std::vector<geometry::Vec3> pts;
  const int n = int(std::lround(std::fabs(to_deg - from_deg) / step_deg));
  for (int k = 0; k <= n; ++k) {
    const double a = (from_deg + (to_deg - from_deg) * k / n) * std::numbers::pi / 180;
    // As written with 6 decimals.
    const double u = std::round((c0 + r * std::cos(a)) * 1e6) / 1e6, v = std::round((c1 + r * std::sin(a)) * 1e6) / 1e6;
    switch (plane) {
      case Plane::XY: pts.push_back({u, v, fixed}); break;
      case Plane::ZX: pts.push_back({v, fixed, u}); break;  // first = Z, second = X
      case Plane::YZ: pts.push_back({fixed, u, v}); break;  // first = Y, second = Z
    }
  }
  return pts;
}

ArcFitOptions two_sided(double tol) {
  ArcFitOptions o;
  o.tolerance = tol;
  o.controller_arc_tolerance = kDollar12;
  return o;
}

void expect_within(const std::vector<geometry::Vec3>& pts, const std::vector<FittedMove>& moves, double tol) {
  const std::vector<geometry::Vec3> path = cut_path(gcode_of(pts, moves), kDollar12);
  ASSERT_FALSE(path.empty());
  EXPECT_LT(norm(path.back() - pts.back()), 1e-9);
  for (const geometry::Vec3& p : pts) EXPECT_LE(distance_to_path(p, path), tol + 1e-9) << p.x << " " << p.y << " " << p.z;
}

}  // namespace

// A circle in each plane, counter-clockwise in the plane's (first, second)
// axes, which is G3 in all three (G18: from +Z towards +X, seen from +Y).
TEST(ArcFit, CircleInEachPlaneIsOneArc) {
  for (Plane plane : {Plane::XY, Plane::ZX, Plane::YZ}) {
    for (bool reverse : {false, true}) {
      SCOPED_TRACE(int(plane) * 10 + int(reverse));
      std::vector<geometry::Vec3> pts = circle_points(plane, 3, -2, 25, 10, 150, 2, 7);
      if (reverse) std::reverse(pts.begin(), pts.end());
      const auto moves = fit_arcs(pts, two_sided(0.01));
      ASSERT_EQ(moves.size(), 1u);
      const FittedMove& m = moves[0];
      EXPECT_TRUE(m.arc);
      EXPECT_EQ(m.plane, plane);
      EXPECT_EQ(m.clockwise, reverse);
      EXPECT_NEAR(m.radius, 25, 1e-3);
      EXPECT_NEAR(m.sweep, 140 * std::numbers::pi / 180, 1e-4);
      const geometry::Vec3 centre = pts[0] + m.center_offset;
      const geometry::Vec3 want = plane == Plane::XY ? geometry::Vec3{3, -2, 7} : plane == Plane::ZX ? geometry::Vec3{-2, 7, 3} : geometry::Vec3{7, 3, -2};
      // Off the plane the offset is zero; in it the centre is the circle's.
      const geometry::Vec3 off_plane = plane == Plane::XY ? geometry::Vec3{0, 0, 1} : plane == Plane::ZX ? geometry::Vec3{0, 1, 0} : geometry::Vec3{1, 0, 0};
      EXPECT_EQ(dot(m.center_offset, off_plane), 0);
      const geometry::Vec3 in_plane_error = (centre - want) - off_plane * dot(centre - want, off_plane);
      EXPECT_LT(norm(in_plane_error), 1e-3);
      EXPECT_EQ(m.to, pts.back());
      expect_within(pts, moves, 0.01);
    }
  }
}

// The direction our interpreter gives the written G2/G3 takes the points'
// way round: the chords pass the middle point, not the far side of the circle.
TEST(ArcFit, WrittenDirectionRunsThroughThePoints) {
  for (Plane plane : {Plane::XY, Plane::ZX, Plane::YZ}) {
    const std::vector<geometry::Vec3> pts = circle_points(plane, 0, 0, 10, 200, 300, 2.5, 1);
    const auto moves = fit_arcs(pts, two_sided(0.005));
    ASSERT_EQ(moves.size(), 1u);
    int arcs = 0;
    const auto path = cut_path(gcode_of(pts, moves), kDollar12, &arcs);
    EXPECT_EQ(arcs, 1);
    EXPECT_LT(distance_to_path(pts[pts.size() / 2], path), 0.005);
    // The lines name the plane: G18 / G19 before the arc where not G17.
    const auto lines = gcode_of(pts, moves);
    const std::string want = plane == Plane::XY ? "G3" : plane == Plane::ZX ? "G18G3" : "G19G3";
    EXPECT_EQ(lines.back().rfind(want, 0), 0u) << lines.back();
  }
}

TEST(ArcFit, StraightRunStaysLines) {
  std::vector<geometry::Vec3> pts;
  for (int k = 0; k <= 50; ++k) pts.push_back({k * 0.1, 2 + k * 0.05, -1});
  const auto moves = fit_arcs(pts, two_sided(0.01));
  ASSERT_EQ(moves.size(), 50u);
  for (std::size_t k = 0; k < moves.size(); ++k) {
    EXPECT_FALSE(moves[k].arc);
    EXPECT_EQ(moves[k].to, pts[k + 1]);
  }
}

// Two arcs meeting at a kink (tangents 60 degrees apart): split there.
TEST(ArcFit, KinkSplitsTheArcs) {
  std::vector<geometry::Vec3> pts = circle_points(Plane::XY, 0, 0, 20, 0, 60, 2, 0);
  const geometry::Vec3 kink = pts.back();
  // The second arc starts at the kink and turns the other way.
  std::vector<geometry::Vec3> second = circle_points(Plane::XY, 0, 0, 15, 180, 120, 2, 0);
  const geometry::Vec3 shift = kink - second.front();
  for (std::size_t k = 1; k < second.size(); ++k) pts.push_back(second[k] + shift);
  const auto moves = fit_arcs(pts, two_sided(0.01));
  ASSERT_EQ(moves.size(), 2u);
  EXPECT_TRUE(moves[0].arc && moves[1].arc);
  EXPECT_EQ(moves[0].to, kink);
  EXPECT_FALSE(moves[0].clockwise);
  EXPECT_TRUE(moves[1].clockwise);
  EXPECT_NEAR(moves[0].radius, 20, 1e-3);
  EXPECT_NEAR(moves[1].radius, 15, 1e-3);
  expect_within(pts, moves, 0.01);
}

// Noise of +-0.003 mm on a circle, tolerance 0.01: still one arc, within it.
TEST(ArcFit, NoisyCircleWithinTolerance) {
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> noise(-0.003, 0.003);
  std::vector<geometry::Vec3> pts = circle_points(Plane::ZX, 0, 0, 30, 30, 80, 1, 0);
  for (std::size_t k = 1; k + 1 < pts.size(); ++k) {
    pts[k].x += noise(rng);
    pts[k].z += noise(rng);
  }
  const auto moves = fit_arcs(pts, two_sided(0.01));
  EXPECT_LE(moves.size(), 2u);
  EXPECT_TRUE(moves[0].arc);
  expect_within(pts, moves, 0.01);
  // The same noise with a tolerance below it cannot be one arc.
  EXPECT_GT(fit_arcs(pts, two_sided(0.0025)).size(), 2u);
}

// GRBL's $12 is part of the budget: a tolerance below the chords' sag fits
// no long arc; an exact controller ($12 = 0) takes them.
TEST(ArcFit, ControllerChordsTakeTheirShare) {
  const std::vector<geometry::Vec3> pts = circle_points(Plane::XY, 0, 0, 10, 0, 90, 1, 0);
  auto o = two_sided(0.001);
  const auto few = fit_arcs(pts, o);
  for (const auto& m : few) EXPECT_LT(m.sweep, 0.2);
  o.controller_arc_tolerance = 0;
  EXPECT_EQ(fit_arcs(pts, o).size(), 1u);
}

// Nearly straight runs (radius over the cap) and a huge radius stay lines.
TEST(ArcFit, HugeRadiusStaysLines) {
  const std::vector<geometry::Vec3> pts = circle_points(Plane::XY, 0, 0, 5000, 90, 89.9, 0.001, 0);
  for (const auto& m : fit_arcs(pts, two_sided(0.01))) EXPECT_FALSE(m.arc);
}

TEST(ArcFit, BadOptionsAreRefused) {
  const std::vector<geometry::Vec3> pts{{0, 0, 0}, {1, 0, 0}};
  auto o = two_sided(-1);
  EXPECT_THROW(fit_arcs(pts, o), std::invalid_argument);
  o = two_sided(0.01);
  o.max_radius = 0;
  EXPECT_THROW(fit_arcs(pts, o), std::invalid_argument);
  EXPECT_TRUE(fit_arcs({}, two_sided(0.01)).empty());
  EXPECT_TRUE(fit_arcs({{1, 2, 3}}, two_sided(0.01)).empty());
}

// Random polylines (fixed seed): pieces of circles in random planes, with
// noise, straight stretches and kinks. Every point within the tolerance of
// the path the controller cuts, and many fewer moves than points.
TEST(ArcFit, RandomPolylinesStayWithinTolerance) {
  std::mt19937 rng(20261125);
  std::uniform_real_distribution<double> unit(0, 1);
  std::size_t points = 0, moves_total = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const double tol = 0.003 + 0.02 * unit(rng);
    const double noise = tol * 0.4 * unit(rng);
    std::vector<geometry::Vec3> pts{{0, 0, 0}};
    const Plane plane = trial % 3 == 0 ? Plane::XY : trial % 3 == 1 ? Plane::ZX : Plane::YZ;
    double heading = unit(rng) * 2 * std::numbers::pi;
    double u = 0, v = 0;
    for (int piece = 0; piece < 6; ++piece) {
      const double r = 2 + 60 * unit(rng);
      const double turn = (unit(rng) < 0.2 ? 0 : (unit(rng) < 0.5 ? -1 : 1) / r);  // curvature; 0: straight
      const double step = 0.05 + 0.3 * unit(rng);
      const int n = 5 + int(40 * unit(rng));
      if (unit(rng) < 0.3) heading += (unit(rng) - 0.5) * 2;  // a kink
      for (int k = 0; k < n; ++k) {
        heading += turn * step;
        u += step * std::cos(heading);
        v += step * std::sin(heading);
        const double nu = (unit(rng) - 0.5) * 2 * noise, nv = (unit(rng) - 0.5) * 2 * noise;
        const double a = std::round((u + nu) * 1e6) / 1e6, b = std::round((v + nv) * 1e6) / 1e6;
        pts.push_back(plane == Plane::XY ? geometry::Vec3{a, b, 1} : plane == Plane::ZX ? geometry::Vec3{b, 2, a} : geometry::Vec3{3, a, b});
      }
    }
    const auto moves = fit_arcs(pts, two_sided(tol));
    SCOPED_TRACE(trial);
    expect_within(pts, moves, tol);
    points += pts.size();
    moves_total += moves.size();
  }
  RecordProperty("points", int(points));
  RecordProperty("moves", int(moves_total));
  EXPECT_LT(moves_total * 3, points);
}

// Over material (a raster row's CL profile in an upright plane): the cut
// path is never below the profile, its points nor its segments, and at most
// the tolerance above its points; convex and concave stretches both arc.
TEST(ArcFit, MaterialBelowNeverGoesUnderTheProfile) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0, 1);
  int arcs = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const bool along_x = trial % 2 == 0;
    const double tol = 0.004 + 0.02 * unit(rng);
    // z(s): a sum of bumps, sampled every 0.05 mm, then rounded up like the program's Z.
    const double a1 = 2 * unit(rng), w1 = 0.1 + 0.3 * unit(rng), a2 = unit(rng), w2 = 0.5 + unit(rng);
    std::vector<geometry::Vec3> pts;
    for (int k = 0; k <= 600; ++k) {
      const double s = k * 0.05;
      double z = a1 * std::sin(w1 * s) + a2 * std::cos(w2 * s + 1);
      z = std::ceil(z * 1000 - 1e-6) / 1000;
      pts.push_back(along_x ? geometry::Vec3{s, 4, z} : geometry::Vec3{-2, s, z});
    }
    ArcFitOptions o = two_sided(tol);
    o.material_below = true;
    const auto moves = fit_arcs(pts, o);
    int trial_arcs = 0;
    const auto path = cut_path(gcode_of(pts, moves), kDollar12, &trial_arcs);
    arcs += trial_arcs;
    SCOPED_TRACE(trial);
    for (const auto& m : moves)
      if (m.arc) {
        EXPECT_EQ(m.plane, along_x ? Plane::ZX : Plane::YZ);
      }
    // The path's height over a row position, by its (monotone) chords.
    auto path_z = [&](double s) {
      for (std::size_t k = 0; k + 1 < path.size(); ++k) {
        const double s0 = along_x ? path[k].x : path[k].y, s1 = along_x ? path[k + 1].x : path[k + 1].y;
        if (s >= s0 - 1e-12 && s <= s1 + 1e-12) {
          const double f = s1 > s0 ? (s - s0) / (s1 - s0) : 0;
          return path[k].z + f * (path[k + 1].z - path[k].z);
        }
      }
      ADD_FAILURE() << "row position " << s << " is not on the path";
      return HUGE_VAL;
    };
    double worst_under = 0, worst_over = 0;
    for (std::size_t k = 0; k + 1 < pts.size(); ++k) {
      // The profile's segments, densely: never above the path.
      for (int f = 0; f <= 10; ++f) {
        const geometry::Vec3 q = pts[k] + (pts[k + 1] - pts[k]) * (f / 10.0);
        worst_under = std::max(worst_under, q.z - path_z(along_x ? q.x : q.y));
      }
      worst_over = std::max(worst_over, distance_to_path(pts[k], path));
    }
    EXPECT_LE(worst_under, 1e-9);
    EXPECT_LE(worst_over, tol + 1e-9);
  }
  EXPECT_GT(arcs, 200);
}

namespace {

// Winding test: whether p lies inside the closed polygon (x, y).
bool inside_polygon(const geometry::Vec3& p, const std::vector<geometry::Vec3>& poly) {
  bool in = false;
  for (std::size_t k = 0, m = poly.size() - 1; k < poly.size(); m = k++) {
    const geometry::Vec3 &a = poly[k], &b = poly[m];
    if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) in = !in;
  }
  return in;
}

double distance_to_polygon(const geometry::Vec3& p, const std::vector<geometry::Vec3>& poly) {
  double best = HUGE_VAL;
  for (std::size_t k = 0; k < poly.size(); ++k)
    best = std::min(best, distance_to_segment(p, poly[k], poly[(k + 1) % poly.size()]));
  return best;
}

}  // namespace

// Waterlines: wavy level loops round a boss (clockwise: the boss on the
// right) and round a pocket (counter-clockwise: its walls on the right),
// bulging both ways. The controller's cut never enters the material and
// passes every point within the tolerance; runs off the level stay lines.
TEST(ArcFit, MaterialRightNeverCrossesIntoTheWall) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 1);
  int arcs = 0;
  for (int trial = 0; trial < 24; ++trial) {
    const bool boss = trial % 2 == 0;
    const double tol = 0.003 + 0.02 * unit(rng);
    const double r0 = 4 + 6 * unit(rng), a1 = 0.3 + 0.8 * unit(rng), a2 = 0.3 * unit(rng);
    const int k1 = 2 + int(4 * unit(rng)), k2 = 5 + int(5 * unit(rng));
    std::vector<geometry::Vec3> loop;
    const int n = int(std::ceil(2 * std::numbers::pi * r0 / 0.05));
    for (int k = 0; k < n; ++k) {
      // Boss: clockwise (angle decreasing); pocket: counter-clockwise.
      const double t = (boss ? -1.0 : 1.0) * 2 * std::numbers::pi * k / n;
      const double r = r0 + a1 * std::sin(k1 * t) + a2 * std::cos(k2 * t + 1);
      loop.push_back({std::round(r * std::cos(t) * 1e6) / 1e6, std::round(r * std::sin(t) * 1e6) / 1e6, -2.5});
    }
    std::vector<geometry::Vec3> pts = loop;
    pts.push_back(loop.front());
    ArcFitOptions o = two_sided(tol);
    o.material_below = true;  // as the finishing program sets it: rows are G18/G19, waterlines G17
    o.material_right = true;
    const auto moves = fit_arcs(pts, o);
    int trial_arcs = 0;
    const auto path = cut_path(gcode_of(pts, moves), kDollar12, &trial_arcs);
    arcs += trial_arcs;
    SCOPED_TRACE(trial);
    for (const auto& m : moves)
      if (m.arc) {
        EXPECT_EQ(m.plane, Plane::XY);
      }
    // The material: inside the loop round a boss, outside it round a pocket.
    double worst_in = 0;
    for (std::size_t k = 0; k + 1 < path.size(); ++k)
      for (int f = 0; f <= 8; ++f) {
        const geometry::Vec3 q = path[k] + (path[k + 1] - path[k]) * (f / 8.0);
        if (inside_polygon(q, loop) == boss) worst_in = std::max(worst_in, distance_to_polygon(q, loop));
      }
    double worst_far = 0;
    for (const geometry::Vec3& p : pts) worst_far = std::max(worst_far, distance_to_path(p, path));
    EXPECT_LE(worst_in, 1e-6);
    EXPECT_LE(worst_far, tol + 1e-9);
  }
  EXPECT_GT(arcs, 100);
}

TEST(ArcFit, LongStretchFittedInParallelChunksIsTheSerialFit) {
  // A raster at one height over level ground: rows along X with bumps (ZX
  // arcs) and noise, joined by links along Y at the same height, so no point
  // is a corner that would cut the stretch: the fit runs in chunks on
  // several threads and stitches them (arc_fit.cpp). The moves must be the
  // serial fit's, exactly.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> noise(-2e-4, 2e-4);
  std::vector<geometry::Vec3> pts;
  const double step = 0.05, z0 = 1.0;
  for (int row = 0; row < 12; ++row) {
    const double y = row * 0.5;
    for (int k = 0; k <= 2000; ++k) {
      const double x = row % 2 ? 100 - k * step : k * step;
      // A bump of radius 4 every 20 mm, 1 mm high; level ground between.
      const double u = std::fmod(x, 20.0) - 10.0;
      double z = z0;
      if (std::fabs(u) < 2.8) z += std::sqrt(16 - u * u) - 3.0 + (row % 3 == 0 ? noise(rng) : 0.0);
      pts.push_back({std::round(x * 1000) / 1000, y, std::max(z0, std::round(z * 1000) / 1000)});
    }
  }
  ASSERT_GT(pts.size(), 20000u);
  for (const bool one_sided : {false, true}) {
    ArcFitOptions o = two_sided(0.01);
    o.material_below = o.material_right = one_sided;
    ArcFitOptions serial = o;
    serial.parallel = false;
    const std::vector<FittedMove> par = fit_arcs(pts, o), ser = fit_arcs(pts, serial);
    int arcs = 0;
    ASSERT_EQ(par.size(), ser.size()) << "one-sided " << one_sided;
    for (std::size_t k = 0; k < par.size(); ++k) {
      const FittedMove &a = par[k], &b = ser[k];
      ASSERT_TRUE(a.arc == b.arc && a.to == b.to && a.plane == b.plane && a.clockwise == b.clockwise &&
                  a.center_offset == b.center_offset && a.radius == b.radius && a.sweep == b.sweep)
          << "move " << k << " of " << par.size() << ", one-sided " << one_sided;
      arcs += a.arc;
    }
    EXPECT_GT(arcs, 100) << "one-sided " << one_sided;  // the bumps (level ground stays lines)
  }
}
