// V-bits, tapered ball-noses and grown ones in the exact CL engine: specs,
// profiles against their geometry, every contact (facet, edge, vertex)
// against brute force on random primitives, the band formulas against the
// flat / ball / bull-nose closed forms, and known answers.
#include <gtest/gtest.h>

#include <cmath>
#include <iomanip>
#include <random>
#include <vector>

#include "../../src/cam/cl_contact.hpp"
#include "cam/cl_cutter_tools.hpp"
#include "cam/cl_oracle.hpp"
#include "cam/cl_test_meshes.hpp"
#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/stock.hpp"
#include "cncstream/jobs/toolpath_job.hpp"

using namespace cncstream;

namespace {

const double kPi = std::acos(-1.0);

std::vector<cam::Cutter> new_cutters() {
  return {cam::Cutter::vbit(60, 6), cam::Cutter::vbit(90, 8, 1.5), cam::Cutter::tapered_ball(1, 5, 3.175),
          cam::Cutter::tapered_ball(3, 20, 9), cam::Cutter::vbit(150, 10)};
}

// The profile of the cutter grown by g, by brute force: the lowest point of
// the balls of radius g centred on its meridian curve (mirrored through the
// axis, with the wall above the rim), heights from the grown tip.
double grown_height_brute(const cam::Cutter& c, double g, double rho) {
  const cl_oracle::Tool t = cl_oracle::tool_of(c);
  const double R = c.radius;
  auto f = [&](double p) {  // p in [-R, R]: a point of the meridian
    const double d = std::clamp(rho - p, -g, g);
    return t.h(std::fabs(p)) - std::sqrt(std::max(0.0, g * g - d * d));
  };
  // Convex in p on the window |rho - p| <= g: golden section, then the window ends.
  const double a = std::max(-R, rho - g), b = std::min(R, rho + g);
  const double p = cl_oracle::golden_argmin(f, a, b, 300);
  return std::min({f(p), f(a), f(b)}) + g;
}

// Max |engine - oracle| over nodes around one primitive mesh.
double worst_error(const geometry::Mesh& m, const cam::Cutter& c, const cl_oracle::Tool& t, std::mt19937& rng, int nodes) {
  const geometry::Box3 b = m.bounds();
  const double R = c.radius;
  std::uniform_real_distribution<double> X(b.lo.x - R, b.hi.x + R), Y(b.lo.y - R, b.hi.y + R);
  cam::ClOptions o;
  o.floor = -100.0;
  const cam::ClEngine e(m, c, o);
  double worst = 0;
  for (int k = 0; k < nodes; ++k) {
    const double x = X(rng), y = Y(rng);
    double best = cl_oracle::kNone;
    for (std::size_t f = 0; f < m.triangles.size(); ++f)
      best = std::max(best, cl_oracle::facet_drop(m.corner(f, 0), m.corner(f, 1), m.corner(f, 2), t, x, y));
    bool on_floor = false;
    const double z = e.height_at(x, y, on_floor);
    // Nodes on the rim to rounding may count either way.
    const double d = cl_oracle::xy_distance(m.corner(0, 0), m.corner(0, 1), m.corner(0, 2), x, y);
    const bool on_rim = std::fabs(d - R) <= 1e-9 * R;
    if (best == cl_oracle::kNone || on_floor) {
      if ((best == cl_oracle::kNone) != on_floor && !on_rim) worst = HUGE_VAL;
      continue;
    }
    worst = std::max(worst, std::fabs(z - best));
    // The grid node at the same place gives the same height (to rounding:
    // where two primitives meet, the one met first may win by an ulp).
    const cam::ClGrid g = e.compute(cam::GridSpec{x, y, 1, 1, 1, 1});
    EXPECT_NEAR(g.z[0], z, 1e-12 * (1 + std::fabs(z))) << std::setprecision(17) << x << "," << y;
  }
  return worst;
}

}  // namespace

TEST(ClCutters, SpecsAndAngles) {
  const cam::Cutter v = cam::parse_cutter_spec("vbit:60:12.7");
  EXPECT_EQ(v.type, cam::CutterType::VBit);
  EXPECT_DOUBLE_EQ(v.radius, 6.35);
  EXPECT_DOUBLE_EQ(v.half_angle_deg, 30);
  EXPECT_EQ(v.spec(), "vbit:60:12.7");
  EXPECT_EQ(cam::parse_cutter_spec("vbit:30side:1/2in").spec(), "vbit:60:12.7");
  const cam::Cutter vt = cam::parse_cutter_spec("vbit:90:6:0.5");
  EXPECT_DOUBLE_EQ(vt.tip_radius, 0.25);
  EXPECT_EQ(cam::parse_cutter_spec(vt.spec()).tip_radius, 0.25);
  const cam::Cutter t = cam::parse_cutter_spec("taper:1:3.58:6.35");
  EXPECT_EQ(t.type, cam::CutterType::TaperedBall);
  EXPECT_DOUBLE_EQ(t.corner_radius, 0.5);
  EXPECT_DOUBLE_EQ(t.half_angle_deg, 3.58);
  EXPECT_DOUBLE_EQ(t.radius, 3.175);
  EXPECT_EQ(t.spec(), "taper:1:3.58:6.35");
  EXPECT_DOUBLE_EQ(cam::parse_cutter_spec("taper:1:7.16incl:6.35").half_angle_deg, 3.58);
  EXPECT_DOUBLE_EQ(cam::parse_cutter_spec("taper:1:5").radius, 3.175 / 2);  // default top: 1/8 in
  EXPECT_EQ(cam::parse_cutter_spec("taper:1:5:1/8in").spec(), "taper:1:5:3.175");
  for (const char* bad : {"vbit:60", "vbit:180:6", "vbit:0:6", "vbit:60:6:6", "vbit:60:6:-1", "taper:1",
                          "taper:1:90:6", "taper:1:0:6", "taper:4:5", "taper:1:5:1", "taper:1:5:6:7", "vbit:x:6",
                          "taper:1:5deg:6incl"}) {
    SCOPED_TRACE(bad);
    EXPECT_THROW(cam::parse_cutter_spec(bad), cam::CutterSpecError);
  }
  EXPECT_NE(cam::parse_cutter_spec("taper:1:5").description().find("tapered ball-nose"), std::string::npos);
}

TEST(ClCutters, ProfilesFromGeometry) {
  for (const cam::Cutter& c : new_cutters()) {
    SCOPED_TRACE(c.spec());
    const cl_oracle::Tool t = cl_oracle::tool_of(c);
    for (int k = 0; k <= 1000; ++k) {
      const double rho = c.radius * k / 1000.0;
      ASSERT_NEAR(c.profile_height(rho), t.h(rho), 1e-12 * (1 + t.h(rho))) << rho;
    }
    EXPECT_NEAR(c.profile_top(), t.h(c.radius), 1e-12 * (1 + c.profile_top()));
    // Grown: the offset profile against its brute-force construction.
    for (double g : {0.05, 0.4}) {
      const cam::Cutter gc = cam::grown_cutter(c, g);
      EXPECT_DOUBLE_EQ(gc.radius, c.radius + g);
      double worst = 0, at = 0;
      for (int k = 0; k < 400; ++k) {  // (at the rim itself h is steep: rounding)
        const double rho = gc.radius * k / 400.0;
        const double err = std::fabs(gc.profile_height(rho) - grown_height_brute(c, g, rho));
        if (err > worst) worst = err, at = rho;
      }
      EXPECT_LE(worst, 1e-9) << "grown by " << g << " at rho " << at;
      EXPECT_NEAR(gc.profile_top(), c.profile_top() + g, 1e-12);
    }
  }
  // The tapered ball's tangent point and its top: r cos a, r (1 - sin a).
  const cam::Cutter tb = cam::Cutter::tapered_ball(1, 5, 3.175);
  const double a = 5 * kPi / 180;
  EXPECT_NEAR(tb.profile_height(0.5 * std::cos(a)), 0.5 * (1 - std::sin(a)), 1e-12);
  EXPECT_NEAR(tb.profile_top(), 0.5 * (1 - std::sin(a)) + (1.5875 - 0.5 * std::cos(a)) / std::tan(a), 1e-9);
}

// Every contact against brute force: random triangles (facet interior, and
// its edges and vertices), random segments (a facet collapsed to an edge:
// level, gentle, steep, near vertical, vertical) and single vertices.
TEST(ClCutters, ContactsAgainstBruteForce) {
  std::mt19937 rng(2811);
  std::uniform_real_distribution<double> U(0, 8), Z(0, 4), S(-1, 1);
  std::vector<cam::Cutter> cs = new_cutters();
  cs.push_back(cam::grown_cutter(cam::Cutter::tapered_ball(1, 5, 3.175), 0.3));
  cs.push_back(cam::grown_cutter(cam::Cutter::vbit(90, 8, 1.5), 0.4));
  for (const cam::Cutter& c : cs) {
    SCOPED_TRACE(c.description());
    cl_oracle::Tool t{c.radius, 0.0};
    if (c.grown > 0) t.profile = [c](double rho) { return c.profile_height(rho); };  // checked above
    else t = cl_oracle::tool_of(c);
    double worst_facet = 0, worst_edge = 0, worst_vertex = 0;
    for (int k = 0; k < 12; ++k) {
      const geometry::Vec3 a{U(rng), U(rng), Z(rng)}, b{U(rng), U(rng), Z(rng)}, p{U(rng), U(rng), Z(rng)};
      worst_facet = std::max(worst_facet, worst_error(cl_test::soup({{a, b, p}}), c, t, rng, 12));
      geometry::Vec3 e = b;
      if (k % 4 == 1) e.z = a.z;                                        // level
      if (k % 4 == 2) e = geometry::Vec3{a.x + 0.3 * S(rng), a.y + 0.3 * S(rng), a.z + 3};  // steep
      if (k % 4 == 3) e = geometry::Vec3{a.x + 1e-7, a.y, a.z + 2};               // near vertical
      if (k == 11) e = geometry::Vec3{a.x, a.y, a.z + 2};                         // vertical
      geometry::Mesh seg;
      seg.vertices = {a, e};
      seg.triangles = {{0, 1, 1}};
      worst_edge = std::max(worst_edge, worst_error(seg, c, t, rng, 16));
      geometry::Mesh v;
      v.vertices = {p};
      v.triangles = {{0, 0, 0}};
      worst_vertex = std::max(worst_vertex, worst_error(v, c, t, rng, 8));
    }
    EXPECT_LE(worst_facet, 1e-6);
    EXPECT_LE(worst_edge, 1e-6);
    EXPECT_LE(worst_vertex, 1e-9);
  }
}

// A facet at exactly the slope of a cone band touches along a segment of
// the band: whichever point the engine reports, the height is right, and the
// edges beside it are drawn (the 45-degree chamfer under a 90-degree V-bit).
TEST(ClCutters, FacetAtTheConesSlope) {
  for (const cam::Cutter& c : {cam::Cutter::vbit(90, 6), cam::Cutter::tapered_ball(1, 45, 6)}) {
    SCOPED_TRACE(c.spec());
    // A ridge of two 45-degree chamfers and a flat top, welded.
    auto f = [](double x, double) { return std::min(3.0, std::min(x, 10 - x)); };
    const geometry::Mesh m = cl_test::terrain(0, 0, 10, 10, f);
    const cl_oracle::Tool t = cl_oracle::tool_of(c);
    const std::vector<std::size_t> by_top = cl_oracle::facets_by_top(m);
    const cam::ClEngine e(m, c);
    cam::ClOptions every;
    every.skip_concave_edges = false;
    const cam::ClGrid g = e.compute(cam::GridSpec::covering(-1, 2, 11, 8, 0.61, 0.83));
    const cam::ClGrid full = cam::ClEngine(m, c, every).compute(g.spec);
    double worst = 0;
    for (std::size_t k = 0; k < g.z.size(); ++k) {
      ASSERT_NEAR(g.z[k], full.z[k], 1e-9);
      const double x = g.spec.x(k % g.spec.nx), y = g.spec.y(k / g.spec.nx);
      const cl_oracle::MeshDrop o = cl_oracle::mesh_drop(m, by_top, t, x, y);
      if (o.drop != cl_oracle::kNone) worst = std::max(worst, std::fabs(g.z[k] - o.drop));
    }
    EXPECT_LE(worst, 1e-6);
  }
}

// The band formulas, forced on flat, ball and bull-nose cutters, against the
// generalized APT closed forms the engine uses for them.
TEST(ClCutters, BandFormulasAgreeWithAptClosedForms) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(0, 8), Z(0, 4), N(-3, 11);
  for (const cam::Cutter& c : {cam::Cutter::flat(4), cam::Cutter::ball(5), cam::Cutter::bull(6, 1), cam::Cutter::bull(4, 1.9)}) {
    SCOPED_TRACE(c.spec());
    const cam::cl_detail::CutterShape apt(c), band(c, true);
    ASSERT_FALSE(apt.general);
    ASSERT_TRUE(band.general);
    double worst = 0;
    for (int k = 0; k < 300; ++k) {
      const geometry::Vec3 a{U(rng), U(rng), Z(rng)}, b{U(rng), U(rng), Z(rng)}, p{U(rng), U(rng), Z(rng)};
      const cam::cl_detail::EdgeGeom e = cam::cl_detail::make_edge(a, b);
      const cam::cl_detail::FaceOffset fa = cam::cl_detail::face_offset(a, b, p, apt), fb = cam::cl_detail::face_offset(a, b, p, band);
      ASSERT_EQ(fa.active, fb.active);
      for (int n = 0; n < 10; ++n) {
        const double x = N(rng), y = N(rng);
        const double ea = cam::cl_detail::edge_drop(e, apt, x, y), eb = cam::cl_detail::edge_drop(e, band, x, y);
        ASSERT_EQ(ea == cam::cl_detail::kNoContact, eb == cam::cl_detail::kNoContact) << x << "," << y;
        if (ea != cam::cl_detail::kNoContact) worst = std::max(worst, std::fabs(ea - eb));
        if (fa.active && !fa.horizontal && fa.contains(x, y) && fb.contains(x, y))
          worst = std::max(worst, std::fabs(fa.value(x, y) - fb.value(x, y)));
        EXPECT_NEAR(apt.h(std::hypot(x - a.x, y - a.y)), band.h(std::hypot(x - a.x, y - a.y)), 1e-12);
      }
    }
    EXPECT_LE(worst, 1e-9);
  }
}

// OpenCAMLib's cone edge contact puts the cutter's length where the cone's
// height belongs; the case from the issue (R 5, 45 degrees, the node 2 mm
// from an edge of slope 0.3) against brute force, and the contact on the
// hyperbola in closed form: v = t d / sqrt(m^2 - t^2).
TEST(ClCutters, ConeEdgeContact) {
  const cam::Cutter c = cam::Cutter::vbit(90, 10);
  const double t = 0.3, d = 2;
  const geometry::Vec3 A{-20, d, 0}, B{20, d, 40 * t};
  geometry::Mesh m;
  m.vertices = {A, B};
  m.triangles = {{0, 1, 1}};
  const double z = cam::ClEngine(m, c).height_at(0, 0);
  const double oracle = cl_oracle::segment_drop(A, B, cl_oracle::tool_of(c), 0, 0);
  EXPECT_NEAR(z, oracle, 1e-9);
  const double v = t * d / std::sqrt(1 - t * t);  // m = 1
  EXPECT_NEAR(z, 20 * t + t * v - std::hypot(d, v), 1e-12);
}

// Planes at every slope: below the cone's slope the tip (V-bit) or the ball
// (tapered ball) touches; above it the rim.
TEST(ClCutters, InclinedPlanes) {
  for (double a_deg : {0.0, 10.0, 30.0, 44.0, 46.0, 60.0, 80.0, 86.0}) {
    for (double phi_deg : {0.0, 37.0, 210.0}) {
      const double a = a_deg * kPi / 180, phi = phi_deg * kPi / 180;
      auto plane = [&](double x, double y) { return 5 + std::tan(a) * (x * std::cos(phi) + y * std::sin(phi)); };
      auto P = [&](double x, double y) { return geometry::Vec3{x, y, plane(x, y)}; };
      const geometry::Mesh m = cl_test::welded({{P(-50, -50), P(50, -50), P(50, 50)}, {P(-50, -50), P(-50, 50), P(50, 50)}});
      for (const cam::Cutter& c : new_cutters()) {
        SCOPED_TRACE(c.spec() + " a=" + std::to_string(a_deg) + " phi=" + std::to_string(phi_deg));
        const double cone = (90 - c.half_angle_deg) * kPi / 180;  // the cone's own slope
        double offset;
        if (a > cone) offset = c.radius * std::tan(a) - c.profile_top();
        else if (c.type == cam::CutterType::VBit) offset = c.tip_radius * std::tan(a);
        else offset = c.corner_radius * (1 / std::cos(a) - 1);
        const cam::ClGrid g = cam::ClEngine(m, c).compute(cam::GridSpec::covering(-30, -30, 30, 30, 1.7, 1.3));
        for (std::size_t j = 0; j < g.spec.ny; ++j)
          for (std::size_t i = 0; i < g.spec.nx; ++i)
            ASSERT_NEAR(g.at(i, j), plane(g.spec.x(i), g.spec.y(j)) + offset, 1e-9 * (1 + std::tan(a)));
      }
    }
  }
}

// The simulator's removal (stock.hpp) sweeps the same profiles: the lowest
// height a straight cut reaches above a point against brute force (the tip
// moving along the segment, the profile convex: golden section in t).
TEST(ClCutters, SweptRemovalAgainstBruteForce) {
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> U(0, 6), Z(-2, 2);
  for (const cam::Cutter& c : new_cutters()) {
    SCOPED_TRACE(c.spec());
    const cl_oracle::Tool t = cl_oracle::tool_of(c);
    double worst = 0;
    int reached = 0;
    for (int k = 0; k < 200; ++k) {
      const geometry::Vec3 a{U(rng), U(rng), Z(rng)};
      const geometry::Vec3 b = k % 5 == 0 ? geometry::Vec3{a.x, a.y, a.z + 1} : k % 5 == 1 ? geometry::Vec3{U(rng), U(rng), a.z} : geometry::Vec3{U(rng), U(rng), Z(rng)};
      const double x = U(rng), y = U(rng);
      auto surface = [&](double s) {
        const geometry::Vec3 p = a + (b - a) * s;
        const double rho = std::hypot(x - p.x, y - p.y);
        return rho > c.radius ? HUGE_VAL : p.z + t.h(rho);
      };
      // Where the disc covers the point: an interval of s; bisect its ends, then golden section.
      const double got = cam::swept_lowest_height(a, b, c, x, y);
      double best = std::min(surface(0), surface(1));
      const double s_min = cl_oracle::golden_argmin([&](double s) {
        const geometry::Vec3 p = a + (b - a) * s;
        return std::hypot(x - p.x, y - p.y);
      }, 0, 1, 200);
      if (std::isfinite(surface(s_min))) {
        double lo = 0, hi = s_min, lo2 = s_min, hi2 = 1;
        for (int it = 0; it < 200 && std::isinf(surface(lo)); ++it) {
          const double m = 0.5 * (lo + hi);
          (std::isinf(surface(m)) ? lo : hi) = m;
          if (hi - lo < 1e-15) lo = hi;
        }
        for (int it = 0; it < 200 && std::isinf(surface(hi2)); ++it) {
          const double m = 0.5 * (lo2 + hi2);
          (std::isinf(surface(m)) ? hi2 : lo2) = m;
          if (hi2 - lo2 < 1e-15) hi2 = lo2;
        }
        best = std::min(best, surface(cl_oracle::golden_argmin(surface, lo, hi2, 300)));
      }
      if (!std::isfinite(best)) {
        EXPECT_FALSE(std::isfinite(got) && got < 1e100) << k;
        continue;
      }
      ++reached;
      worst = std::max(worst, std::fabs(got - best));
    }
    EXPECT_GT(reached, 50);
    EXPECT_LE(worst, 1e-6);
  }
}

TEST(ClCutters, DepthLimitFromGeometry) {
  // As deep as a ball of the top diameter, never deeper than the flutes.
  EXPECT_DOUBLE_EQ(jobs::default_max_depth(cam::Cutter::tapered_ball(1, 5, 3.175)), 3.175 / 2);
  const cam::Cutter shallow = cam::Cutter::vbit(150, 10);  // a cone 1.34 mm high
  EXPECT_NEAR(jobs::default_max_depth(shallow), 5 / std::tan(75 * kPi / 180), 1e-12);
}
