// Finishing by scallop height, piece by piece: rows spaced by the slope
// across them (RowSpacing, build_raster's row_gap), steep stretches judged
// along the moves (skip_steep), and the waterline's level at the foot of the
// walls over a flat area.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "cam/cl_test_meshes.hpp"
#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/pencil.hpp"
#include "cncstream/cam/raster.hpp"
#include "cncstream/cam/row_spacing.hpp"
#include "cncstream/cam/slope_map.hpp"
#include "cncstream/cam/steep_shallow.hpp"
#include "cncstream/cam/waterline.hpp"
#include "cncstream/geometry/mesh.hpp"
#include "support/v_groove.hpp"

using namespace cncstream;

namespace {

constexpr double kDeg = std::numbers::pi / 180;

// A height field z(y) (the same for every x) as a CL grid.
cam::ClGrid profile_grid(double (*z)(double), double step) {
  cam::ClGrid g;
  g.spec = cam::GridSpec::covering(0, 0, 10, 30, step, step);
  g.z.resize(g.spec.size());
  g.on_floor.assign(g.spec.size(), 0);
  for (std::size_t j = 0; j < g.spec.ny; ++j)
    for (std::size_t i = 0; i < g.spec.nx; ++i) g.at(i, j) = z(g.spec.y(j));
  return g;
}

// Level up to y = 10, a 30 degree ramp up to y = 15, level again, a
// 70 degree wall from y = 22 to 23, level beyond.
double ramp_and_wall(double y) {
  const double t30 = std::tan(30 * kDeg), t70 = std::tan(70 * kDeg);
  const double ramp = std::clamp(y - 10, 0.0, 5.0) * t30;
  const double wall = std::clamp(y - 22, 0.0, 1.0) * t70;
  return ramp + wall;
}

// An open surface of two triangles a side: the plane z = 0 for y < 10, a
// ramp of `deg` up to y = 15, level beyond, over x in [0, 30].
geometry::Mesh ramp_mesh(double deg) {
  geometry::Mesh m;
  const double h = 5 * std::tan(deg * kDeg);
  const double ys[] = {-5, 10, 15, 35}, zs[] = {0, 0, h, h};
  for (int k = 0; k < 4; ++k) {
    m.vertices.push_back({-5, ys[k], zs[k]});
    m.vertices.push_back({35, ys[k], zs[k]});
  }
  for (std::uint32_t k = 0; k < 3; ++k) {
    const std::uint32_t a = 2 * k;
    m.triangles.push_back({a, a + 1, a + 3});
    m.triangles.push_back({a, a + 3, a + 2});
  }
  return m;
}

}  // namespace

TEST(RowSpacing, GapFollowsTheSlopeAcrossTheRowsUpToTheSteepAngle) {
  const cam::ClGrid g = profile_grid(&ramp_and_wall, 0.25);
  const double widest = 0.8, steep = 45 * kDeg;
  const cam::RowSpacing rows(g, true, widest, steep);
  // Level ground, a grid line beyond either row included.
  EXPECT_DOUBLE_EQ(rows.gap(2, 2.8), widest);
  EXPECT_DOUBLE_EQ(rows.gap(17, 17.8), widest);
  // On the ramp: cos 30 degrees.
  EXPECT_NEAR(rows.gap(12, 12.7), std::cos(30 * kDeg) * widest, 1e-9);
  // A band reaching the ramp from the level ground takes the ramp's.
  EXPECT_NEAR(rows.gap(9, 9.8), std::cos(30 * kDeg) * widest, 1e-9);
  // The 70 degree wall is the waterlines' ground: it does not count (nor
  // do the nodes at its kinks, which the central differences make 54
  // degrees steep).
  EXPECT_DOUBLE_EQ(rows.gap(22, 22.8), widest);
  // Slopes along the rows do not count: rows along Y see level ground.
  const cam::RowSpacing along_y(g, false, widest, steep);
  EXPECT_DOUBLE_EQ(along_y.gap(3, 3.8), widest);
  EXPECT_THROW(cam::RowSpacing(g, true, 0, steep), std::invalid_argument);
  EXPECT_THROW(cam::RowSpacing(g, true, widest, 90 * kDeg), std::invalid_argument);
}

TEST(RowSpacing, RasterRowsCloseInOverTheRampOnlyAndStayExact) {
  const geometry::Mesh m = ramp_mesh(30);
  const cam::Cutter ball = cam::parse_cutter_spec("ball:3");
  const cam::ClEngine engine(m, ball);
  cam::ClGrid ground = engine.compute(cam::GridSpec::covering(0, 0, 30, 30, 0.25, 0.25));
  const double widest = 0.8;
  const cam::RowSpacing spacing(ground, true, widest, 45 * kDeg);
  cam::RasterOptions o;
  o.stepover = widest;
  o.step = 0.1;
  o.lattice = cam::XYLattice{0.001, 0, 0};
  o.row_gap = [&spacing](double a, double b) { return spacing.gap(a, b); };
  const cam::XYBounds b{0, 0, 30, 30};
  const cam::RasterPath path = cam::build_raster(engine, b, o);
  ASSERT_GE(path.rows.size(), 30u);
  EXPECT_NEAR(path.stepover, widest, 1e-9);
  EXPECT_NEAR(path.stepover_min, std::cos(30 * kDeg) * widest, widest / 32 + 1e-9);
  EXPECT_NEAR(path.rows.front().front().y, 0, 1e-12);
  EXPECT_NEAR(path.rows.back().front().y, 30, 1e-9);
  ASSERT_EQ(path.links.size(), path.rows.size() - 1);
  std::size_t narrow = 0, wide = 0;
  for (std::size_t r = 0; r + 1 < path.rows.size(); ++r) {
    const double ya = path.rows[r].front().y, yb = path.rows[r + 1].front().y;
    const double d = yb - ya;
    // On the lattice, never wider than the gap allows.
    EXPECT_NEAR(std::round(ya / 0.001) * 0.001, ya, 1e-9);
    EXPECT_LE(d, spacing.gap(ya, yb) + 1e-9) << "rows at " << ya << " and " << yb;
    // The ball's CL rounds the ramp's kinks within its radius: rows far from
    // it (beyond the radius and a grid line) are widest apart.
    if (yb < 10 - 1.5 - 0.6 || (ya > 15 + 1.5 + 0.6 && r + 2 < path.rows.size())) {
      EXPECT_NEAR(d, widest, 1e-9) << "rows at " << ya << " and " << yb;
      ++wide;
    }
    if (ya > 11 && yb < 14) {
      EXPECT_LT(d, std::cos(30 * kDeg) * widest + 1e-9);
      ++narrow;
    }
    // Every vertex of a row is on the exact CL (rows of one spacing share
    // a grid; the vertices are its nodes).
    for (const geometry::Vec3& p : path.rows[r]) ASSERT_NEAR(p.z, engine.height_at(p.x, p.y), 1e-9);
  }
  EXPECT_GT(wide, 20u);
  EXPECT_GE(narrow, 2u);
  // A gap under the spacings' quantum (widest / 32) is kept on the lattice,
  // not rounded down to one lattice step.
  cam::RasterOptions tight = o;
  tight.row_gap = [](double, double) { return 0.0137; };
  const cam::RasterPath dense = cam::build_raster(engine, cam::XYBounds{0, 0, 5, 1}, tight);
  ASSERT_GE(dense.rows.size(), 3u);
  EXPECT_NEAR(dense.rows[1].front().y - dense.rows[0].front().y, 0.013, 1e-9);
  EXPECT_EQ(dense.rows.size(), 78u);  // 76 gaps of 0.013 to 0.988, one of 0.012
  // keep_grid needs even rows.
  o.keep_grid = true;
  EXPECT_THROW(cam::build_raster(engine, b, o), std::invalid_argument);
}

TEST(SkipSteep, AMoveOverLevelGroundBetweenTwoWallsIsNotBridged) {
  // Level at 0, a steep wall from x = 1 to 2 up to a level top at 5, down
  // again from x = 8 to 9 (slopes along X this time: rows along X).
  cam::ClGrid g;
  g.spec = cam::GridSpec::covering(-2, -2, 12, 2, 0.25, 0.25);
  g.z.resize(g.spec.size());
  g.on_floor.assign(g.spec.size(), 0);
  for (std::size_t j = 0; j < g.spec.ny; ++j)
    for (std::size_t i = 0; i < g.spec.nx; ++i) {
      const double x = g.spec.x(i);
      g.at(i, j) = 5 * (std::clamp(x - 1, 0.0, 1.0) - std::clamp(x - 8, 0.0, 1.0));
    }
  const cam::SlopeMap slope(g);
  // A merged row: up the first wall to a point on it, one long move to a
  // point on the second wall (over the level top), down to the foot.
  const cam::Polyline row = {{-1, 0, 0}, {1.5, 0, 2.5}, {8.5, 0, 2.5}, {11, 0, 0}};
  const cam::SteepSkip s = cam::skip_steep({row}, slope, 45 * kDeg);
  ASSERT_EQ(s.pieces.size(), 1u);
  // Each wall's crossing is bridged (the samples up and down it are
  // steep); the long move over the level top is still cut as it was.
  EXPECT_EQ(s.bridges, 2u);
  const cam::Polyline& p = s.pieces[0];
  bool kept = false;
  for (std::size_t k = 0; k + 1 < p.size(); ++k) {
    kept = kept || (p[k].x <= 3 && p[k + 1].x >= 7 && p[k].z == 2.5 && p[k + 1].z == 2.5);
    EXPECT_FALSE(p[k].x < 1 && p[k + 1].x > 9) << "one bridge over both walls and the level top between them";
  }
  EXPECT_TRUE(kept) << "the move over the level top was bridged";
  EXPECT_EQ(p.front(), row.front());
  EXPECT_EQ(p.back(), row.back());

  // Across one wall alone: bridged over the wall only (its ends on the
  // row's moves, a sample before and after the steep ground), the row's own
  // points before and after kept.
  const cam::Polyline across = {{-1, 0, 0}, {1.25, 0, 1.25}, {1.75, 0, 3.75}, {4, 0, 5}};
  const cam::SteepSkip t = cam::skip_steep({across}, slope, 45 * kDeg);
  ASSERT_EQ(t.pieces.size(), 1u);
  EXPECT_EQ(t.bridges, 1u);
  EXPECT_EQ(t.points_skipped, 2u);
  const cam::Polyline& q = t.pieces[0];
  EXPECT_EQ(q.front(), across.front());
  EXPECT_EQ(q.back(), across.back());
  for (const geometry::Vec3& p : q) {
    EXPECT_DOUBLE_EQ(p.y, 0);
    // Off the row's own points only over the wall and the cell beside it.
    const bool own = std::find(across.begin(), across.end(), p) != across.end();
    if (!own) {
      EXPECT_GE(p.x, 0.5);
      EXPECT_LE(p.x, 2.5);
    }
  }
}

TEST(WaterlineLevels, OneRunsAtTheFootOfTheWallsOverAFlatArea) {
  // A plate 30 x 30 x 2 (the CL drops to the floor beyond it) with a block
  // 10 x 10 x 5 standing on it: with levels 1.3 mm apart from the floor
  // none falls near the plate's top, where the ball meets the block's walls.
  geometry::Mesh m;
  auto box = [&](geometry::Vec3 lo, geometry::Vec3 hi) {
    const auto b = static_cast<std::uint32_t>(m.vertices.size());
    for (int k = 0; k < 8; ++k) m.vertices.push_back({k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z});
    const int f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                          {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    for (auto& t : f) m.triangles.push_back({b + t[0], b + t[1], b + t[2]});
  };
  box({0, 0, 0}, {30, 30, 2});
  box({10, 10, 2}, {20, 20, 7});
  const cam::Cutter ball = cam::parse_cutter_spec("ball:3");
  const cam::ClEngine engine(m, ball);
  const cam::ClGrid grid = engine.compute(cam::GridSpec::covering(-3, -3, 33, 33, 0.25, 0.25));
  const cam::SlopeMap slope(grid);
  cam::WaterlineOptions o;
  o.z_step = 1.3;
  const cam::WaterlinePath with = cam::build_waterline(engine, grid, slope, o);
  o.flat_levels = false;
  const cam::WaterlinePath without = cam::build_waterline(engine, grid, slope, o);
  auto has = [](const std::vector<double>& levels, double z) {
    return std::any_of(levels.begin(), levels.end(), [&](double l) { return std::fabs(l - z) < 1e-9; });
  };
  EXPECT_TRUE(has(with.levels, 2.002));
  EXPECT_FALSE(has(without.levels, 2.002));
  EXPECT_EQ(with.levels.size(), without.levels.size() + 1);  // the floor has its level already; the top is the top
  // At that level the ball runs round the block, its side on the walls.
  std::size_t at_foot = 0;
  for (const cam::Polyline& pl : with.pieces)
    for (const geometry::Vec3& p : pl)
      if (std::fabs(p.z - 2.002) < 1e-9) {
        ++at_foot;
        // The radius from the block (round its corners).
        const double dx = std::max({10 - p.x, 0.0, p.x - 20}), dy = std::max({10 - p.y, 0.0, p.y - 20});
        EXPECT_NEAR(std::hypot(dx, dy), 1.5, 0.01) << p.x << "," << p.y;
      }
  EXPECT_GT(at_foot, 8u);
}

TEST(Pencil, OnePassAlongAVGroovesCreaseOnTheClAndNoneOnAPlane) {
  const geometry::Mesh m = test::v_groove();
  const cam::ClEngine engine(m, cam::parse_cutter_spec("ball:2"));
  cam::PencilOptions o;
  o.lattice = cam::XYLattice{0.001, 0, 0};
  const cam::XYBounds b{10, 2, 30, 18};
  const auto all = [](double, double) { return true; };
  const std::vector<cam::Polyline> passes = cam::pencil_passes(engine, b, o, all);
  ASSERT_EQ(passes.size(), 1u);
  const cam::Polyline& p = passes.front();
  double y0 = HUGE_VAL, y1 = -HUGE_VAL;
  for (const geometry::Vec3& q : p) {
    EXPECT_NEAR(q.x, 20, 0.051);  // on the crease's grid line or the one beside it
    y0 = std::min(y0, q.y);
    y1 = std::max(y1, q.y);
  }
  EXPECT_LT(y0, 2.2);
  EXPECT_GT(y1, 17.8);
  // Every move on or above the exact CL (the ball touches both walls at
  // 1 (sqrt 2 - 1) above the crease, on it; a hair more beside it).
  for (std::size_t k = 0; k + 1 < p.size(); ++k)
    for (int s = 0; s <= 20; ++s) {
      const geometry::Vec3 q = p[k] + (p[k + 1] - p[k]) * (s / 20.0);
      ASSERT_GE(q.z, engine.height_at(q.x, q.y) - 1e-6) << q.x << "," << q.y;
    }
  EXPECT_NEAR(p.front().z, 6 + std::sqrt(2.0) - 1, 0.06);
  // Only where wanted; none on the level top.
  EXPECT_TRUE(cam::pencil_passes(engine, b, o, [](double, double) { return false; }).empty());
  EXPECT_TRUE(cam::pencil_passes(engine, cam::XYBounds{1, 2, 12, 18}, o, all).empty());
}

TEST(WaterlineLevels, SpacedByTheGentlestWallBetweenThem) {
  // Along x: a 40-degree ramp up to a terrace 4 mm high, then a wall up to 8 mm.
  const geometry::Mesh m = cl_test::terrain(0, 0, 40, 160, [](double x, double) {
    return x < 25 ? std::clamp((x - 8) * std::tan(40 * kDeg), 0.0, 4.0) : 8.0;
  });
  const cam::ClEngine engine(m, cam::parse_cutter_spec("ball:2"));
  const cam::ClGrid grid = engine.compute(cam::GridSpec::covering(-2, -2, 42, 42, 0.25, 0.25));
  const cam::SlopeMap slope(grid);
  cam::WaterlineOptions o;
  o.flat_levels = false;
  o.wall_spacing = 1;
  o.wall_angle_deg = 35;
  const cam::WaterlinePath w = cam::build_waterline(engine, grid, slope, o);
  std::vector<double> up(w.levels.rbegin(), w.levels.rend());
  ASSERT_GT(up.size(), 5u);
  // The promise: a node at least 35 degrees steep lies in bands (over the
  // heights to its neighbours, whose differences give its slope) no taller
  // than the spacing times the sine of its slope.
  const std::size_t nx = grid.spec.nx, ny = grid.spec.ny;
  std::size_t walls = 0;
  for (std::size_t j = 1; j + 1 < ny; ++j)
    for (std::size_t i = 1; i + 1 < nx; ++i) {
      const double a = slope.at(i, j);
      if (a < 35 * kDeg || grid.on_floor[j * nx + i]) continue;
      ++walls;
      const double lo = std::min({grid.at(i, j), grid.at(i - 1, j), grid.at(i + 1, j), grid.at(i, j - 1), grid.at(i, j + 1)});
      const double hi = std::max({grid.at(i, j), grid.at(i - 1, j), grid.at(i + 1, j), grid.at(i, j - 1), grid.at(i, j + 1)});
      for (std::size_t k = 0; k + 1 < up.size(); ++k)
        if (up[k + 1] >= lo && up[k] < hi) {
          ASSERT_LE(up[k + 1] - up[k], std::sin(a) + 1e-12) << "node " << i << "," << j << " at " << lo << ".." << hi;
        }
    }
  EXPECT_GT(walls, 100u);
  // Up the ramp the levels are as close as its 40 degrees ask; up the wall's
  // face (below the ball's roll over its top edge) a whole spacing apart.
  bool ramp = false, wall = false;
  for (std::size_t k = 0; k + 1 < up.size(); ++k) {
    const double gap = up[k + 1] - up[k];
    EXPECT_GE(gap, std::sin(35 * kDeg) - 1e-12);
    if (up[k] > 1 && up[k + 1] < 3) {
      ramp = true;
      EXPECT_NEAR(gap, std::sin(40 * kDeg), 0.05) << "at " << up[k];
    }
    if (up[k] > 4.5 && up[k + 1] < 6.5) {
      wall = true;
      EXPECT_GT(gap, 0.9) << "at " << up[k];
    }
  }
  EXPECT_TRUE(ramp);
  EXPECT_TRUE(wall);
  EXPECT_NEAR(w.step_min, std::sin(35 * kDeg), 0.05);
  EXPECT_GT(w.step_max, 0.9);
  EXPECT_LE(w.step_max, 1.0);
  // On the G-code's grid (work zero 0.3 um off the model's) every level
  // prints as it is; the bands still keep to their walls.
  o.lattice = cam::XYLattice{0.001, 0, 0, 0.0003};
  const cam::WaterlinePath gridded = cam::build_waterline(engine, grid, slope, o);
  ASSERT_GT(gridded.levels.size(), 5u);
  for (std::size_t k = 0; k < gridded.levels.size(); ++k) {
    const double steps = (gridded.levels[k] - 0.0003) / 0.001;
    EXPECT_NEAR(steps, std::round(steps), 1e-6) << gridded.levels[k];
    if (k > 0) {
      EXPECT_LE(gridded.levels[k - 1] - gridded.levels[k], 1.0);
    }
  }
  EXPECT_GE(gridded.step_min, std::sin(35 * kDeg) - 0.001);
  o.lattice.reset();
  // Fewer levels than at the gentlest wall's spacing everywhere.
  o.wall_spacing = 0;
  o.z_step = std::sin(35 * kDeg);
  EXPECT_LT(w.levels.size(), cam::build_waterline(engine, grid, slope, o).levels.size());
}
