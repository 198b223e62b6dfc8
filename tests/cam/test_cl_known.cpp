// CL engine known answers: closed forms derived independently of the engine.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "cam/cl_cutter_tools.hpp"
#include "cam/cl_oracle.hpp"
#include "cam/cl_test_meshes.hpp"
#include "cncstream/cam/cl_engine.hpp"

using namespace cncstream;

namespace {

const double kPi = std::acos(-1.0);

std::vector<cam::Cutter> cutters() {
  return {cam::Cutter::flat(6), cam::Cutter::ball(6), cam::Cutter::bull(6, 1), cam::Cutter::bull(6, 2.5), cam::Cutter::ball(1.5),
          cam::Cutter::bull(10, 0.2)};
}

// The same and the cone-based cutters (for the tests that need only h).
std::vector<cam::Cutter> all_cutters() {
  std::vector<cam::Cutter> c = cutters();
  for (const cam::Cutter& n : {cam::Cutter::vbit(60, 6), cam::Cutter::vbit(90, 8, 1.5), cam::Cutter::tapered_ball(1, 5, 3.175),
                          cam::Cutter::tapered_ball(3, 20, 9)})
    c.push_back(n);
  return c;
}

using cl_oracle::tool_of;

double rk_of(const cam::Cutter& c) { return tool_of(c).rk; }
double rc_of(const cam::Cutter& c) { return c.radius - rk_of(c); }

}  // namespace

TEST(ClKnown, BoxTopAndVerticalWalls) {
  // Top at z = 10 over [10, 30]^2, vertical walls down to 0. Inside the top
  // every cutter sits on it; beside a wall the cutter's profile rests on the
  // top edge: z = 10 - h(d), d the distance to the top rectangle; beyond R
  // nothing is touched. (The thesis's bounding-space trimming gouges here.)
  const geometry::Mesh m = cl_test::box({10, 10, 0}, {30, 30, 10});
  for (const cam::Cutter& c : all_cutters()) {
    SCOPED_TRACE(c.spec());
    const cl_oracle::Tool t = tool_of(c);
    cam::ClOptions o;
    o.floor = -5.0;
    const cam::ClGrid g = cam::ClEngine(m, c, o).compute(cam::GridSpec::covering(0.25, 0.25, 39.75, 39.75, 0.5, 0.5));
    for (std::size_t j = 0; j < g.spec.ny; ++j)
      for (std::size_t i = 0; i < g.spec.nx; ++i) {
        const double x = g.spec.x(i), y = g.spec.y(j);
        const double ddx = std::fmax(0.0, std::fmax(10 - x, x - 30)), ddy = std::fmax(0.0, std::fmax(10 - y, y - 30));
        const double d = std::hypot(ddx, ddy);
        const std::size_t k = j * g.spec.nx + i;
        if (d > c.radius) {
          EXPECT_EQ(g.on_floor[k], 1) << x << "," << y;
          EXPECT_EQ(g.z[k], -5.0);
        } else {
          ASSERT_EQ(g.on_floor[k], 0) << x << "," << y;
          ASSERT_NEAR(g.z[k], 10 - t.h(d), 1e-9) << x << "," << y << " d=" << d;
        }
      }
  }
}

TEST(ClKnown, InclinedPlaneEveryCutter) {
  // Plane z = 5 + tan(a) (x cos(phi) + y sin(phi)) as two big triangles (the
  // shared diagonal is coplanar, so it is not drawn: the facets' own contacts
  // must cover it). Offset of a plane at slope a:
  //   ball: R (1/cos a - 1), flat: R tan a, bull: rc tan a + rk (1/cos a - 1).
  for (double a_deg : {0.0, 3.0, 20.0, 45.0, 70.0, 85.0}) {
    for (double phi_deg : {0.0, 37.0, 210.0}) {
      const double a = a_deg * kPi / 180, phi = phi_deg * kPi / 180;
      auto plane = [&](double x, double y) { return 5 + std::tan(a) * (x * std::cos(phi) + y * std::sin(phi)); };
      auto P = [&](double x, double y) { return geometry::Vec3{x, y, plane(x, y)}; };
      const geometry::Mesh m = cl_test::welded({{P(-50, -50), P(50, -50), P(50, 50)}, {P(-50, -50), P(-50, 50), P(50, 50)}});
      for (const cam::Cutter& c : cutters()) {
        SCOPED_TRACE(c.spec() + " a=" + std::to_string(a_deg) + " phi=" + std::to_string(phi_deg));
        const double rk = rk_of(c), rc = rc_of(c);
        const double offset = rc * std::tan(a) + rk * (1 / std::cos(a) - 1);
        const cam::ClEngine e(m, c);
        const cam::ClGrid g = e.compute(cam::GridSpec::covering(-30, -30, 30, 30, 1.7, 1.3));
        for (std::size_t j = 0; j < g.spec.ny; ++j)
          for (std::size_t i = 0; i < g.spec.nx; ++i) {
            const double x = g.spec.x(i), y = g.spec.y(j);
            ASSERT_NEAR(g.at(i, j), plane(x, y) + offset, 1e-9 * (1 + std::tan(a))) << x << "," << y;
          }
        // Points on the shared diagonal's contact line, off the grid.
        for (double s : {-20.0, -3.3, 0.0, 7.1}) {
          const double x = s + (rc * std::cos(phi) + rk * std::sin(a) * std::cos(phi)) * (a > 0 ? -1 : 0);
          const double y = s + (rc * std::sin(phi) + rk * std::sin(a) * std::sin(phi)) * (a > 0 ? -1 : 0);
          EXPECT_NEAR(e.height_at(x, y), plane(x, y) + offset, 1e-9 * (1 + std::tan(a)));
        }
      }
    }
  }
}

TEST(ClKnown, Hemisphere) {
  // Sphere radius S: ball tip = sqrt((S+R)^2 - r^2) - R; bull-nose (torus
  // ring at rc) tip = sqrt((S+rk)^2 - (r-rc)^2) - rk for r >= rc, else S;
  // flat: the highest sphere point within the disc, sqrt(S^2 - (r-R)^2).
  // The mesh is inscribed, so the engine lies below by at most the sagitta.
  const double S = 20;
  const geometry::Mesh m = cl_test::hemisphere(S, 60, 240);
  const double sagitta = 0.01;
  for (const cam::Cutter& c : cutters()) {
    SCOPED_TRACE(c.spec());
    const double R = c.radius, rk = rk_of(c), rc = rc_of(c);
    const cam::ClEngine e(m, c);
    const cam::ClGrid g = e.compute(cam::GridSpec::covering(-17.3, -17.3, 17.3, 17.3, 0.9, 0.9));
    for (std::size_t j = 0; j < g.spec.ny; ++j)
      for (std::size_t i = 0; i < g.spec.nx; ++i) {
        const double r = std::hypot(g.spec.x(i), g.spec.y(j));
        if (r > S - R) continue;  // keep the contact on the hemisphere
        double exact;
        if (c.type == cam::CutterType::Flat) exact = r <= R ? S : std::sqrt(S * S - (r - R) * (r - R));
        else exact = r <= rc ? S : std::sqrt((S + rk) * (S + rk) - (r - rc) * (r - rc)) - rk;
        const double z = g.at(i, j);
        EXPECT_LE(z, exact + 1e-9) << r;
        EXPECT_GE(z, exact - sagitta) << r;
      }
    // At the apex the mesh vertex is on the sphere: exact.
    EXPECT_NEAR(e.height_at(0, 0), S, 1e-12);
  }
}

TEST(ClKnown, SingleVertex) {
  // A facet collapsed to one point is drawn as that vertex: z = v.z - h(rho).
  geometry::Mesh m;
  m.vertices = {{3.3, -1.2, 7.5}};
  m.triangles = {{0, 0, 0}};
  for (const cam::Cutter& c : all_cutters()) {
    SCOPED_TRACE(c.spec());
    const cl_oracle::Tool t = tool_of(c);
    cam::ClOptions o;
    o.floor = 0.0;
    const cam::ClEngine e(m, c, o);
    const cam::ClGrid g = e.compute(cam::GridSpec::covering(-3, -7, 9, 5, 0.37, 0.41));
    for (std::size_t j = 0; j < g.spec.ny; ++j)
      for (std::size_t i = 0; i < g.spec.nx; ++i) {
        const double rho = std::hypot(g.spec.x(i) - 3.3, g.spec.y(j) + 1.2);
        if (rho > c.radius) {
          EXPECT_EQ(g.on_floor[j * g.spec.nx + i], 1);
          EXPECT_EQ(g.at(i, j), 0.0);
        } else {
          EXPECT_NEAR(g.at(i, j), 7.5 - t.h(rho), 1e-12);
        }
      }
  }
}

TEST(ClKnown, SingleEdgeAtSlopes) {
  // A facet collapsed to a segment is drawn as that edge. Ball against a
  // line of slope b at horizontal distance d: tip = z(s0) + sqrt(R^2-d^2)/cos b
  // - R (cylinder). Flat: z(s0) + tan b sqrt(R^2-d^2) (rim point uphill).
  // Both where the contact falls inside the segment; everywhere (and for the
  // bull-nose) against the independent 1-D oracle.
  for (double b_deg : {0.0, 10.0, 30.0, 45.0, 60.0, 80.0, 89.0, 89.99}) {
    const double b = b_deg * kPi / 180;
    const geometry::Vec3 A{-5, -2, 1}, dir = normalized(geometry::Vec3{11, 6, 0});
    const double L = 12.5;
    const geometry::Vec3 B = A + dir * L + geometry::Vec3{0, 0, L * std::tan(b)};
    geometry::Mesh m;
    m.vertices = {A, B};
    m.triangles = {{0, 1, 1}};
    for (const cam::Cutter& c : all_cutters()) {
      SCOPED_TRACE(c.spec() + " slope " + std::to_string(b_deg));
      const double R = c.radius;
      const cl_oracle::Tool t = tool_of(c);
      const cam::ClGrid g = cam::ClEngine(m, c).compute(cam::GridSpec::covering(-9, -6, 11, 9, 0.53, 0.47));
      int closed_form_checks = 0;
      for (std::size_t j = 0; j < g.spec.ny; ++j)
        for (std::size_t i = 0; i < g.spec.nx; ++i) {
          const double x = g.spec.x(i), y = g.spec.y(j);
          const double s0 = (x - A.x) * dir.x + (y - A.y) * dir.y;
          const double d = std::fabs((x - A.x) * dir.y - (y - A.y) * dir.x);
          const double z = g.at(i, j);
          const double oracle = cl_oracle::segment_drop(A, B, t, x, y);
          if (oracle == cl_oracle::kNone) {
            EXPECT_EQ(g.on_floor[j * g.spec.nx + i], 1) << x << "," << y;
            continue;
          }
          EXPECT_GE(z, oracle - 1e-6) << x << "," << y;
          EXPECT_LE(z, oracle + 1e-6) << x << "," << y;
          if (d >= R) continue;
          const double w = std::sqrt(R * R - d * d);
          if (c.type == cam::CutterType::Ball) {
            const double v = w * std::sin(b);  // contact offset along the segment
            if (s0 + v > 1e-6 && s0 + v < L - 1e-6) {
              EXPECT_NEAR(z, A.z + s0 * std::tan(b) + w / std::cos(b) - R, 1e-9 / std::cos(b)) << x << "," << y;
              ++closed_form_checks;
            }
          } else if (c.type == cam::CutterType::Flat && b > 0) {
            if (s0 + w > 1e-6 && s0 + w < L - 1e-6) {
              EXPECT_NEAR(z, A.z + (s0 + w) * std::tan(b), 1e-9 / std::cos(b)) << x << "," << y;
              ++closed_form_checks;
            }
          }
        }
      if (c.type == cam::CutterType::Ball || (c.type == cam::CutterType::Flat && b > 0)) {
        EXPECT_GT(closed_form_checks, 50);
      }
    }
  }
}
