// CL engine against the independent brute-force oracle (cl_oracle.hpp) on
// random triangle soups with awkward facets and on manifold terrains.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "cam/cl_cutter_tools.hpp"
#include "cam/cl_oracle.hpp"
#include "cam/cl_test_meshes.hpp"
#include "cncstream/cam/cl_engine.hpp"

using namespace cncstream;

namespace {

using cl_oracle::tool_of;

// Every node: touched exactly as the oracle says (within tol), else floor.
void expect_matches_oracle(const geometry::Mesh& m, const cam::Cutter& c, const cam::ClGrid& g, double tol) {
  const cl_oracle::Tool t = tool_of(c);
  const std::vector<std::size_t> by_top = cl_oracle::facets_by_top(m);
  int touched = 0;
  for (std::size_t j = 0; j < g.spec.ny; ++j)
    for (std::size_t i = 0; i < g.spec.nx; ++i) {
      const double x = g.spec.x(i), y = g.spec.y(j);
      const cl_oracle::MeshDrop o = cl_oracle::mesh_drop(m, by_top, t, x, y);
      const std::size_t k = j * g.spec.nx + i;
      if (o.drop == cl_oracle::kNone) {
        ASSERT_EQ(g.on_floor[k], 1) << "touched where the oracle finds nothing at " << x << "," << y;
        continue;
      }
      if (g.on_floor[k] && o.distance >= c.radius * (1 - 1e-9)) continue;  // exactly on the rim: either is right
      ++touched;
      ASSERT_EQ(g.on_floor[k], 0) << "untouched at " << x << "," << y << " oracle " << o.drop;
      // No gouge: no facet reaches above the cutter.
      ASSERT_GE(g.z[k], o.drop - tol) << "gouge of " << o.drop - g.z[k] << " at " << x << "," << y;
      // Touched: some facet reaches the cutter.
      ASSERT_LE(g.z[k], o.drop + tol) << "floating above the mesh at " << x << "," << y;
    }
  EXPECT_GT(touched, 0);
}

std::vector<cam::Cutter> cutters() {
  return {cam::Cutter::flat(2),          cam::Cutter::ball(3),        cam::Cutter::bull(4, 1),
          cam::Cutter::bull(6, 2.5),     cam::Cutter::ball(0.6),      cam::Cutter::flat(7),
          cam::Cutter::vbit(60, 5),      cam::Cutter::vbit(90, 6, 1), cam::Cutter::tapered_ball(1, 5, 4)};
}

// A soup with the facets that break naive code: generic, vertical, nearly
// vertical, horizontal, slivers, tiny, collinear, repeated vertex.
geometry::Mesh awkward_soup(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0, 10), Z(0, 5), S(-1, 1);
  auto P = [&] { return geometry::Vec3{U(rng), U(rng), Z(rng)}; };
  std::vector<std::array<geometry::Vec3, 3>> t;
  for (int k = 0; k < 4; ++k) t.push_back({P(), P(), P()});
  {  // vertical facet
    const geometry::Vec3 a = P(), b = P();
    const double s = 0.3 + 0.4 * (S(rng) + 1) / 2;
    t.push_back({a, b, geometry::Vec3{a.x + s * (b.x - a.x), a.y + s * (b.y - a.y), Z(rng) + 2}});
  }
  {  // nearly vertical facet
    const geometry::Vec3 a = P(), b = P();
    t.push_back({a, b, geometry::Vec3{a.x + 0.5 * (b.x - a.x) + 1e-9, a.y + 0.5 * (b.y - a.y), Z(rng) + 3}});
  }
  {  // horizontal facet
    const double z = Z(rng);
    geometry::Vec3 a = P(), b = P(), c = P();
    a.z = b.z = c.z = z;
    t.push_back({a, b, c});
  }
  {  // sliver
    const geometry::Vec3 a = P(), b = P();
    t.push_back({a, b, geometry::Vec3{0.5 * (a.x + b.x) + 1e-3 * S(rng), 0.5 * (a.y + b.y) + 1e-3 * S(rng), 0.5 * (a.z + b.z) + S(rng)}});
  }
  {  // tiny facet
    const geometry::Vec3 a = P();
    t.push_back({a, a + geometry::Vec3{1e-3 * S(rng), 1e-3 * S(rng), 1e-3 * S(rng)}, a + geometry::Vec3{1e-3 * S(rng), 1e-3 * S(rng), 1e-3}});
  }
  {  // collinear (zero area) and a nearly horizontal one
    const geometry::Vec3 a = P(), b = P();
    t.push_back({a, b, a + (b - a) * 0.25});
    geometry::Vec3 c = P(), d = P(), e = P();
    c.z = d.z = 4;
    e.z = 4 + 1e-11;
    t.push_back({c, d, e});
  }
  geometry::Mesh m = cl_test::soup(t);
  // One facet that repeats a vertex index.
  m.triangles.push_back({0, 0, 1});
  return m;
}

}  // namespace

TEST(ClOracle, AwkwardSoups) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const geometry::Mesh m = awkward_soup(seed);
    for (const cam::Cutter& c : cutters()) {
      SCOPED_TRACE(c.spec() + " seed " + std::to_string(seed));
      cam::ClOptions o;
      o.floor = -10.0;
      const cam::ClGrid g = cam::ClEngine(m, c, o).compute(cam::GridSpec::covering(-2, -2, 12, 12, 0.61, 0.59));
      expect_matches_oracle(m, c, g, 1e-6);
    }
  }
}

TEST(ClOracle, ManifoldTerrainWithPlateausValleysAndCliff) {
  // Welded height field: bumps (ridges and valleys), a flat plateau (coplanar
  // facets), a tilted flat region and a near-cliff. Manifold edges in valleys
  // and on flats are not drawn, so this checks that leaving them out is exact.
  auto f = [](double x, double y) {
    double z = 2 + std::sin(0.9 * x) * std::cos(0.7 * y) + 0.3 * std::sin(2.3 * x + 1.1 * y);
    if (x > 6 && y > 6) z = 3.5;             // plateau
    if (x < 3 && y > 7) z = 1 + 0.2 * x;     // tilted flat
    if (x > 8 && y < 3) z += 6;              // cliff
    return z;
  };
  const geometry::Mesh m = cl_test::terrain(0, 0, 10, 12, f);
  for (const cam::Cutter& c : cutters()) {
    SCOPED_TRACE(c.spec());
    const cam::ClGrid g = cam::ClEngine(m, c).compute(cam::GridSpec::covering(-1, -1, 11, 11, 0.53, 0.57));
    expect_matches_oracle(m, c, g, 1e-6);
  }
}

// The default engine leaves out valley and coplanar edges and trims ridge
// edges to the band where their contact normal lies between their facets'
// normals; `skip_concave_edges = false` draws every edge in full.
TEST(ClOracle, LeavingOutConcaveEdgesChangesNothing) {
  auto f = [](double x, double y) {
    double z = std::sin(1.3 * x) * std::cos(1.1 * y) + 0.1 * x;
    if (std::hypot(x - 5, y - 5) < 2) z = 1.5;
    return z;
  };
  const geometry::Mesh m = cl_test::terrain(0, 0, 10, 40, f);
  for (const cam::Cutter& c : cutters()) {
    SCOPED_TRACE(c.spec());
    cam::ClOptions all;
    all.skip_concave_edges = false;
    const cam::ClEngine skip(m, c), full(m, c, all);
    EXPECT_LT(skip.stats().edges_drawn, full.stats().edges_drawn * 3 / 4);
    EXPECT_EQ(full.stats().edges_drawn, full.stats().edges);
    const cam::GridSpec spec = cam::GridSpec::covering(-1, -1, 11, 11, 0.07, 0.09);
    const cam::ClGrid a = skip.compute(spec), b = full.compute(spec);
    double worst = 0;
    for (std::size_t k = 0; k < a.z.size(); ++k) worst = std::fmax(worst, std::fabs(a.z[k] - b.z[k]));
    EXPECT_LE(worst, 1e-8);  // rounding of near-tangent contacts
    EXPECT_EQ(a.on_floor, b.on_floor);
  }
}

TEST(ClOracle, RandomTerrainsAllCutters) {
  for (unsigned seed : {7u, 8u}) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> H(0, 3);
    std::vector<double> h(81);
    for (auto& v : h) v = H(rng);
    auto f = [&](double x, double y) {
      const int i = static_cast<int>(std::lround(x)), j = static_cast<int>(std::lround(y));
      return h[static_cast<std::size_t>(j * 9 + i)];
    };
    const geometry::Mesh m = cl_test::terrain(0, 0, 8, 8, f);
    for (const cam::Cutter& c : cutters()) {
      SCOPED_TRACE(c.spec() + " seed " + std::to_string(seed));
      const cam::ClGrid g = cam::ClEngine(m, c).compute(cam::GridSpec::covering(-1.5, -1.5, 9.5, 9.5, 0.5, 0.5));
      expect_matches_oracle(m, c, g, 1e-6);
    }
  }
}
