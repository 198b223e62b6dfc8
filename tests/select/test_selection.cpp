// Cutter-type selection: the corrected d_base formulas, d on inclined planes,
// the choice on a sphere and a torus (the thesis's test surfaces), and the
// scallops from the exact cut simulation against the 2-D estimate.
#include <gtest/gtest.h>

#include <cmath>

#include "cam/cl_test_meshes.hpp"
#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/cutter_selection.hpp"
#include "cncstream/cam/path_machining.hpp"
#include "cncstream/cam/raster.hpp"
#include "cncstream/cam/scallop.hpp"

using namespace cncstream;

namespace {
constexpr double kDeg = M_PI / 180;

// Ball and bull-nose of 6 mm with rc = rk = R / 2, as in the thesis.
cam::CutterPair thesis_pair() { return cam::CutterPair(cam::Cutter::ball(6), cam::Cutter::bull(6, 1.5)); }

// An X raster over [-10, 10]^2 at stepover s, machined on `sim` from a stock
// at `top`; the scallops and the passes' y.
struct Scallops {
  cam::ScallopMap map;
  std::vector<double> rows;
};
Scallops raster_scallops(const geometry::Mesh& mesh, const cam::Cutter& cut, double s, const cam::GridSpec& sim, const cam::DesignHeights& design,
                         double top) {
  const cam::ClEngine e(mesh, cut);
  cam::RasterOptions o;
  o.stepover = s;
  o.step = 0.1;
  const cam::RasterPath path = cam::build_raster(e, {-10, -10, 10, 10}, o);
  const auto machined = cam::machine_path(sim, std::vector<double>(sim.size(), top), cam::raster_pieces(path), cut);
  Scallops out;
  for (const auto& r : path.rows) out.rows.push_back(r.front().y);
  out.map = cam::scallops_from_cut(sim, machined, design, out.rows, true);
  return out;
}
}  // namespace

TEST(Selection, SwitchAnglesOfTheCorrectedFormulas) {
  const cam::CutterPair c = thesis_pair();
  const double vol = cam::switch_angle(c.rc(), cam::d_base(cam::RemovalCriterion::Volume, c.rc(), c.rk())) / kDeg;
  const double area = cam::switch_angle(c.rc(), cam::d_base(cam::RemovalCriterion::Area, c.rc(), c.rk())) / kDeg;
  EXPECT_NEAR(vol, 34.7, 0.05);
  EXPECT_NEAR(area, 21.8, 0.1);
  // The formulas scale with the cutter: the angles depend on rk / R only.
  EXPECT_NEAR(cam::switch_angle(3.0, cam::d_base(cam::RemovalCriterion::Volume, 3.0, 3.0)) / kDeg, vol, 1e-9);
  EXPECT_THROW(cam::CutterPair(cam::Cutter::ball(6), cam::Cutter::bull(8, 1)), std::invalid_argument);
  EXPECT_THROW(cam::CutterPair(cam::Cutter::flat(6), cam::Cutter::bull(6, 1)), std::invalid_argument);
}

// On a plane inclined at alpha the engine's CL grids give d = rc (1 - sin a) / cos a.
TEST(Selection, DOnInclinedPlanesMatchesTheClosedForm) {
  const cam::CutterPair c = thesis_pair();
  const double dv = cam::d_base(cam::RemovalCriterion::Volume, c.rc(), c.rk());
  for (double a_deg : {0.0, 10.0, 25.0, 34.0, 36.0, 50.0, 65.0}) {
    SCOPED_TRACE(a_deg);
    const double t = std::tan(a_deg * kDeg);
    const geometry::Mesh plane = cl_test::terrain(0, 0, 40, 4, [&](double x, double) { return t * x; });
    const cam::GridSpec g = cam::GridSpec::covering(12, 12, 28, 28, 0.5, 0.5);
    const cam::ClGrid ball = cam::ClEngine(plane, c.ball).compute(g), bull = cam::ClEngine(plane, c.radiused).compute(g);
    const cam::RemovalChoice ch = cam::choose_by_removal(c, ball, bull);
    const double expect = cam::inclined_plane_d(c.rc(), a_deg * kDeg);
    for (std::size_t k = 0; k < g.size(); ++k) {
      ASSERT_NEAR(ch.d[k], expect, 1e-6);
      EXPECT_EQ(ch.by_volume[k], expect > dv ? cam::Choice::Radiused : cam::Choice::Ball);
      EXPECT_NEAR(ch.slope_deg[k], a_deg, 1e-6);
    }
  }
}

// The sphere and the torus: the radiused cutter wins below the switch
// angle, the ball above it.
TEST(Selection, SphereAndTorusSwitchAtTheAngle) {
  const cam::CutterPair c = thesis_pair();
  const double sw = cam::switch_angle(c.rc(), cam::d_base(cam::RemovalCriterion::Volume, c.rc(), c.rk())) / kDeg;
  const geometry::Mesh sphere = cl_test::terrain(-40, -40, 80, 240, [](double x, double y) {
    return std::sqrt(std::max(0.0, 35.0 * 35.0 - x * x - y * y));
  });
  const geometry::Mesh torus = cl_test::terrain(-40, -40, 80, 240, [](double x, double y) {
    const double q = std::hypot(x, y) - 22;
    return std::sqrt(std::max(0.0, 12.0 * 12.0 - q * q));
  });
  for (const geometry::Mesh* m : {&sphere, &torus}) {
    SCOPED_TRACE(m == &sphere ? "sphere" : "torus");
    const cam::GridSpec g = cam::GridSpec::covering(-30, -30, 30, 30, 0.4, 0.4);
    const cam::ClGrid ball = cam::ClEngine(*m, c.ball).compute(g), bull = cam::ClEngine(*m, c.radiused).compute(g);
    const cam::RemovalChoice ch = cam::choose_by_removal(c, ball, bull);
    // On a curved surface the two cutters touch at different points (the
    // ball R sin a from its axis, the radiused rc + rk sin a), so the plane's
    // rule holds up to the curvature: nearly everywhere 2 degrees away from
    // the switch.
    std::size_t below = 0, above = 0, below_ok = 0, above_ok = 0;
    for (std::size_t k = 0; k < g.size(); ++k) {
      const double s = ch.slope_deg[k];
      if (!std::isfinite(s) || s > 70) continue;
      if (s < sw - 2) {
        ++below;
        below_ok += ch.by_volume[k] == cam::Choice::Radiused;
      } else if (s > sw + 2) {
        ++above;
        above_ok += ch.by_volume[k] == cam::Choice::Ball;
      }
    }
    EXPECT_GT(below, 1000u);
    EXPECT_GT(above, 1000u);
    EXPECT_GE(double(below_ok), 0.995 * double(below)) << below_ok << " of " << below;
    EXPECT_GE(double(above_ok), 0.98 * double(above)) << above_ok << " of " << above;
    const cam::SlopeProfile p = cam::slope_profile(ch, 5);
    EXPECT_NEAR(p.switch_deg_volume, sw, 2.5);
  }
}

TEST(Selection, TwoDimensionalScallopEstimate) {
  const cam::Cutter ball = cam::Cutter::ball(6), bull = cam::Cutter::bull(6, 1.5);
  EXPECT_NEAR(cam::scallop_2d(ball, 1.0, 0), 3 - std::sqrt(9 - 0.25), 1e-5);
  EXPECT_NEAR(cam::scallop_2d(bull, 1.0, 0), 0, 1e-9);  // flat bottom wider than the stepover
  EXPECT_GT(cam::scallop_2d(bull, 1.0, 30 * kDeg), cam::scallop_2d(ball, 1.0, 30 * kDeg));
  // A ball's scallop on a slope: the passes are s / cos(a) apart along it;
  // vertically the cusp is taller by 1 / cos(a).
  const double a = 30 * kDeg, w = 1.0 / std::cos(a);
  EXPECT_NEAR(cam::scallop_2d(ball, 1.0, a), (3 - std::sqrt(9 - w * w / 4)) / std::cos(a), 1e-4);
}

// Table 4.1's shape: on the sphere's flat top the radiused cutter leaves no
// scallop (stepover below its flat width), the ball always leaves one; the
// cut simulation agrees with the 2-D estimate on the flat.
TEST(Selection, CutSimulationScallopsOnTheSphere) {
  const cam::CutterPair c = thesis_pair();
  const geometry::Mesh sphere = cl_test::terrain(-40, -40, 80, 240, [](double x, double y) {
    return std::sqrt(std::max(0.0, 35.0 * 35.0 - x * x - y * y));
  });
  const double s = 1.0;
  const cam::GridSpec sim = cam::GridSpec::covering(-8, -8, 8, 8, 0.1, s / 10);
  const cam::DesignHeights design = cam::design_heights(sphere, sim);
  for (const cam::Cutter& cut : {c.ball, c.radiused}) {
    SCOPED_TRACE(cut.spec());
    const Scallops sc = raster_scallops(sphere, cut, s, sim, design, 40.0);
    const cam::ScallopMap& m = sc.map;
    const std::vector<double>& rows = sc.rows;
    ASSERT_GT(m.stats.samples, 100u);
    // Near the apex (slope < 2 degrees within 1.2 mm of the top) compare with the 2-D estimate.
    const double flat = cam::scallop_2d(cut, s, 0);
    double near_apex = 0;
    for (std::size_t p = 0; p + 1 < rows.size(); ++p)
      if (std::fabs(rows[p]) < 1.2 && std::fabs(rows[p + 1]) < 1.2)
        for (std::size_t col = 0; col < m.columns; ++col)
          if (std::fabs(sim.x(col)) < 1.2) near_apex = std::max(near_apex, m.pair_scallop[p * m.columns + col]);
    if (cut.type == cam::CutterType::Bull) {
      // The flat bottom spans the stepover: what is left near the apex is
      // only the sphere's own fall between passes, s^2 / (8 * 35).
      EXPECT_LT(m.stats.min, s * s / (8 * 35.0) + 1e-3);
      EXPECT_LT(near_apex, s * s / (8 * 35.0) + 1e-3);
    } else {
      EXPECT_GT(m.stats.min, 0.02);
      EXPECT_NEAR(near_apex, flat, 0.01);
    }
    EXPECT_GT(m.stats.max, m.stats.mean);
  }
}

// Where the surface is flat and the stepover below the flat width (2 rc) the
// radiused cutter leaves no scallop at all; the ball leaves R - sqrt(R^2 - s^2/4).
TEST(Selection, NoScallopOnAFlatForTheRadiusedCutter) {
  const cam::CutterPair c = thesis_pair();
  const geometry::Mesh flat = cl_test::terrain(-20, -20, 40, 8, [](double, double) { return 2.0; });
  const double s = 2.5;  // below 2 rc = 3
  const cam::GridSpec sim = cam::GridSpec::covering(-6, -6, 6, 6, 0.1, s / 10);
  const cam::DesignHeights design = cam::design_heights(flat, sim);
  for (const cam::Cutter& cut : {c.ball, c.radiused}) {
    const cam::ScallopMap m = raster_scallops(flat, cut, s, sim, design, 5.0).map;
    ASSERT_GT(m.stats.samples, 100u);
    const double expect = cut.type == cam::CutterType::Ball ? 3 - std::sqrt(9 - s * s / 4) : 0.0;
    EXPECT_NEAR(m.stats.max, expect, 2e-3) << cut.spec();
    EXPECT_NEAR(m.stats.min, expect, 2e-3) << cut.spec();
    EXPECT_NEAR(cam::scallop_2d(cut, s, 0), expect, 1e-4);
  }
}
