// CL engine API: thread independence, streamed tiles, the point query, the
// floor, and input errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <random>
#include <stdexcept>
#include <vector>

#include "cam/cl_test_meshes.hpp"
#include "cncstream/cam/cl_engine.hpp"

using namespace cncstream;

namespace {

geometry::Mesh bumpy() {
  return cl_test::terrain(0, 0, 40, 60, [](double x, double y) {
    double z = 3 + std::sin(x / 3) * std::cos(y / 4) + 0.2 * std::sin(1.7 * x + y);
    if (std::hypot(x - 25, y - 15) < 6) z = 5.5;  // plateau with near-vertical sides
    return z;
  });
}

std::vector<cam::Cutter> cutters() { return {cam::Cutter::ball(6), cam::Cutter::flat(3), cam::Cutter::bull(8, 1.5)}; }

}  // namespace

TEST(ClEngine, SameResultForAnyThreadCount) {
  const geometry::Mesh m = bumpy();
  // Big enough for many tiles (128 x 128 nodes each).
  const cam::GridSpec spec = cam::GridSpec::covering(-3, -3, 43, 43, 0.13, 0.11);
  for (const cam::Cutter& c : cutters()) {
    SCOPED_TRACE(c.spec());
    cam::ClOptions one;
    one.threads = 1;
    const cam::ClGrid a = cam::ClEngine(m, c, one).compute(spec);
    for (unsigned n : {2u, 3u, 0u}) {
      cam::ClOptions o;
      o.threads = n;
      const cam::ClGrid b = cam::ClEngine(m, c, o).compute(spec);
      EXPECT_EQ(a.z, b.z) << n << " threads";
      EXPECT_EQ(a.on_floor, b.on_floor) << n << " threads";
    }
  }
}

TEST(ClEngine, TilesConcatenateToTheWholeGrid) {
  const geometry::Mesh m = bumpy();
  const cam::GridSpec spec = cam::GridSpec::covering(-3, -3, 43, 43, 0.17, 0.19);
  for (const cam::Cutter& c : cutters()) {
    SCOPED_TRACE(c.spec());
    cam::ClOptions o;
    o.max_tile_bytes = spec.nx * 9 * 37 + 5;  // 37 rows per tile, last one short
    const cam::ClEngine e(m, c, o);
    const cam::ClGrid whole = e.compute(spec);
    std::vector<double> z;
    std::vector<std::uint8_t> fl;
    std::size_t expect_j0 = 0, tiles = 0;
    e.compute_tiles(spec, [&](const cam::ClTile& t) {
      EXPECT_EQ(t.j0, expect_j0);
      EXPECT_LE(t.grid.spec.ny, 37u);
      EXPECT_EQ(t.grid.spec.nx, spec.nx);
      EXPECT_DOUBLE_EQ(t.grid.spec.y0, spec.y(t.j0));
      EXPECT_EQ(t.grid.z.size(), t.grid.spec.size());
      expect_j0 += t.grid.spec.ny;
      ++tiles;
      z.insert(z.end(), t.grid.z.begin(), t.grid.z.end());
      fl.insert(fl.end(), t.grid.on_floor.begin(), t.grid.on_floor.end());
    });
    EXPECT_EQ(tiles, (spec.ny + 36) / 37);
    EXPECT_EQ(z, whole.z);
    EXPECT_EQ(fl, whole.on_floor);
  }
}

TEST(ClEngine, HeightAtAgreesWithGridNodes) {
  const geometry::Mesh m = bumpy();
  const cam::GridSpec spec = cam::GridSpec::covering(-4, -4, 44, 44, 0.7, 0.9);
  for (const cam::Cutter& c : cutters()) {
    SCOPED_TRACE(c.spec());
    const cam::ClEngine e(m, c);
    const cam::ClGrid g = e.compute(spec);
    int touched = 0;
    for (std::size_t j = 0; j < spec.ny; ++j)
      for (std::size_t i = 0; i < spec.nx; ++i) {
        bool on_floor = false;
        const double z = e.height_at(spec.x(i), spec.y(j), on_floor);
        ASSERT_EQ(on_floor, g.on_floor[j * spec.nx + i] == 1) << i << "," << j;
        ASSERT_NEAR(z, g.at(i, j), 1e-9) << i << "," << j;
        touched += !on_floor;
      }
    EXPECT_GT(touched, 100);
    // Off the nodes: a fine grid shifted by a fraction of the step.
    cam::GridSpec fine = spec;
    fine.x0 += 0.31;
    fine.y0 += 0.47;
    fine.nx -= 1;
    fine.ny -= 1;
    const cam::ClGrid f = e.compute(fine);
    for (std::size_t j = 0; j < fine.ny; j += 3)
      for (std::size_t i = 0; i < fine.nx; i += 3) ASSERT_NEAR(e.height_at(fine.x(i), fine.y(j)), f.at(i, j), 1e-9);
  }
}

// The batched check must give the answer of asking point by point, for
// every cutter family, with the limit where it matters: at the CL of some
// point of the line (a contour's chord), a hair above and below it, under
// the floor, and off the part.
TEST(ClEngine, FirstAboveIsThePointByPointAnswer) {
  const geometry::Mesh m = bumpy();
  std::vector<cam::Cutter> all = cutters();
  all.push_back(cam::Cutter::tapered_ball(1, 5, 3.175));
  all.push_back(cam::Cutter::vbit(60, 6));
  std::mt19937 rng(28);
  std::uniform_real_distribution<double> at(-5, 45), unit(0, 1);
  for (const bool lowest : {false, true}) {
    for (const cam::Cutter& c : all) {
      SCOPED_TRACE(c.spec() + (lowest ? " (floor is lowest)" : ""));
      cam::ClOptions o;
      o.floor_is_lowest = lowest;
      o.floor = 2.5;
      const cam::ClEngine e(m, c, o);
      std::size_t found = 0, none = 0;
      for (int trial = 0; trial < 400; ++trial) {
        cam::SampledLine line{at(rng), at(rng), 0, 0, 1 + static_cast<std::size_t>(unit(rng) * 300)};
        // Short chords (a waterline's) and long moves across cells.
        const double len = trial % 2 ? 0.05 + unit(rng) : 2 + 20 * unit(rng), dir = 7 * unit(rng);
        line.bx = line.ax + len * std::cos(dir);
        line.by = line.ay + len * std::sin(dir);
        if (trial % 3 == 0) {
          line.ox = 0.01 * unit(rng);
          line.oy = -0.01 * unit(rng);
        }
        const std::size_t k0 = static_cast<std::size_t>(unit(rng) * double(line.n) / 2);
        const std::size_t k1 = std::min(line.n, k0 + static_cast<std::size_t>(unit(rng) * double(line.n)));
        const std::size_t pick = k0 + static_cast<std::size_t>(unit(rng) * double(k1 - k0));
        const double cl = e.height_at(line.x(pick), line.y(pick));
        const double limits[] = {cl, cl + 1e-9, cl - 1e-9, cl + 0.05, cl - 0.3, 1.0, 100.0};
        for (const double limit : limits) {
          std::size_t expect = k1 + 1;
          for (std::size_t k = k0; k <= k1; ++k)
            if (e.height_at(line.x(k), line.y(k)) > limit) {
              expect = k;
              break;
            }
          ASSERT_EQ(e.first_above(line, k0, k1, limit), expect)
              << "line " << line.ax << "," << line.ay << " -> " << line.bx << "," << line.by << " n " << line.n << " ["
              << k0 << ", " << k1 << "] limit " << limit;
          (expect <= k1 ? found : none) += 1;
        }
      }
      // Both answers came up many times.
      EXPECT_GT(found, 400u);
      EXPECT_GT(none, 400u);
    }
  }
}

TEST(ClEngine, FloorAndUntouchedNodes) {
  const geometry::Mesh m = cl_test::box({0, 0, 2}, {10, 10, 5});
  const cam::GridSpec spec = cam::GridSpec::covering(-20, -20, 30, 30, 1, 1);
  const cam::ClEngine by_default(m, cam::Cutter::ball(4));
  EXPECT_EQ(by_default.floor(), 2.0);  // the mesh's lowest z
  const cam::ClGrid g = by_default.compute(spec);
  EXPECT_EQ(g.floor, 2.0);
  EXPECT_EQ(g.at(0, 0), 2.0);
  EXPECT_EQ(g.on_floor[0], 1);
  EXPECT_EQ(g.at(25, 25), 5.0);  // (5, 5): on the top
  EXPECT_EQ(g.on_floor[25 * spec.nx + 25], 0);
  cam::ClOptions o;
  o.floor = -1.5;
  const cam::ClEngine low(m, cam::Cutter::ball(4), o);
  EXPECT_EQ(low.compute(spec).at(0, 0), -1.5);
  EXPECT_EQ(low.height_at(-15, 3), -1.5);
  // Touched but below the floor stays where it touches (never raised into the part).
  cam::ClOptions high;
  high.floor = 4.5;
  const cam::ClGrid h = cam::ClEngine(m, cam::Cutter::ball(4), high).compute(spec);
  EXPECT_NEAR(h.at(19, 25), 5 - (2 - std::sqrt(4 - 1.0)), 1e-12);  // (-1, 5): 1 mm outside the wall
  EXPECT_EQ(h.on_floor[25 * spec.nx + 19], 0);
}

// A tapered ball's flutes end 12.9 mm above its tip: beside a 3 mm wall, out
// near its reach, it touches the wall's top rim with its tip far below the
// part's bottom. With floor_is_lowest such a node comes out at the floor
// (still touched), in the grid and the point query alike; nodes above it
// and untouched ones are as before.
TEST(ClEngine, FloorIsLowestRaisesTouchedNodesBelowTheFloorToIt) {
  const geometry::Mesh m = cl_test::box({0, 0, 0}, {10, 10, 3});
  const cam::Cutter taper = cam::parse_cutter_spec("taper:1:5:3.175");
  const cam::GridSpec spec = cam::GridSpec::covering(-2, -2, 12, 12, 0.1, 0.1);
  const cam::ClEngine surface(m, taper);
  cam::ClOptions o;
  o.floor_is_lowest = true;
  const cam::ClEngine lowest(m, taper, o);
  const cam::ClGrid a = surface.compute(spec), b = lowest.compute(spec);
  // (-1.5, 5): 1.5 mm outside the wall, the cone touches the rim 11.3 mm above the tip.
  const std::size_t i = 5, j = 70, k = j * spec.nx + i;
  ASSERT_NEAR(spec.x(i), -1.5, 1e-9);
  EXPECT_NEAR(a.at(i, j), 3 - taper.profile_height(1.5), 1e-9);
  EXPECT_LT(a.at(i, j), -8);
  EXPECT_EQ(b.at(i, j), 0.0);
  EXPECT_EQ(b.on_floor[k], 0);
  EXPECT_EQ(lowest.height_at(spec.x(i), spec.y(j)), 0.0);
  EXPECT_NEAR(surface.height_at(spec.x(i), spec.y(j)), a.at(i, j), 1e-9);
  std::size_t raised = 0;
  for (std::size_t n = 0; n < spec.size(); ++n) {
    EXPECT_EQ(a.on_floor[n], b.on_floor[n]) << n;
    EXPECT_EQ(b.z[n], std::max(a.z[n], 0.0)) << n;
    raised += a.z[n] < 0;
  }
  EXPECT_GT(raised, 4 * 100u);  // a ring all round the box
}

TEST(ClEngine, EmptyMeshIsAllFloor) {
  const geometry::Mesh m;
  const cam::ClEngine e(m, cam::Cutter::flat(6));
  const cam::ClGrid g = e.compute(cam::GridSpec::covering(0, 0, 5, 5, 1, 1));
  for (std::size_t k = 0; k < g.z.size(); ++k) {
    EXPECT_EQ(g.z[k], 0.0);
    EXPECT_EQ(g.on_floor[k], 1);
  }
  EXPECT_EQ(e.height_at(1, 1), 0.0);
}

TEST(ClEngine, RejectsBadInput) {
  const geometry::Mesh m = cl_test::box({0, 0, 0}, {1, 1, 1});
  EXPECT_THROW(cam::ClEngine(m, cam::Cutter::ball(0)), std::invalid_argument);
  EXPECT_THROW(cam::ClEngine(m, cam::Cutter{cam::CutterType::Bull, 3, 4}), std::invalid_argument);
  geometry::Mesh bad = m;
  bad.triangles.push_back({0, 1, 99});
  try {
    cam::ClEngine e(bad, cam::Cutter::ball(2));
    FAIL() << "accepted a facet with a vertex index out of range";
  } catch (const std::invalid_argument& err) {
    EXPECT_NE(std::string(err.what()).find("facet 12"), std::string::npos) << err.what();
  }
  geometry::Mesh nan = m;
  nan.vertices[3].y = std::nan("");
  EXPECT_THROW(cam::ClEngine(nan, cam::Cutter::ball(2)), std::invalid_argument);
  const cam::ClEngine e(m, cam::Cutter::ball(2));
  cam::GridSpec s = cam::GridSpec::covering(0, 0, 1, 1, 0.5, 0.5);
  s.dx = 0;
  EXPECT_THROW(e.compute(s), std::invalid_argument);
  s.dx = 0.5;
  s.y0 = HUGE_VAL;
  EXPECT_THROW(e.compute_tiles(s, [](const cam::ClTile&) {}), std::invalid_argument);
  cam::ClOptions o;
  o.floor = std::nan("");
  EXPECT_THROW(cam::ClEngine(m, cam::Cutter::ball(2), o), std::invalid_argument);
}

TEST(ClEngine, StatsCountWhatIsDrawn) {
  const geometry::Mesh m = cl_test::box({0, 0, 0}, {10, 10, 3});
  const cam::ClEngine e(m, cam::Cutter::ball(2));
  const cam::ClEngineStats& s = e.stats();
  EXPECT_EQ(s.facets, 12u);
  EXPECT_EQ(s.face_offsets, 4u);  // top and bottom; the walls are vertical
  EXPECT_EQ(s.edges, 18u);        // 12 box edges + 6 face diagonals
  EXPECT_EQ(s.vertices, 8u);
  // The top and bottom diagonals are coplanar: left out. Every other edge
  // borders a vertical wall, which never lets an edge go.
  EXPECT_EQ(s.edges_drawn, 16u);
  EXPECT_EQ(s.vertices_drawn, 0u);
}

// Streamed tiles report the fraction of the whole grid inside each tile, and
// a checkpoint that throws stops the grid there (a cancelled `clgrid`).
TEST(ClEngine, TilesCheckpointSpansTheWholeGridAndCanStopIt) {
  const geometry::Mesh m = bumpy();
  const cam::GridSpec spec = cam::GridSpec::covering(-3, -3, 43, 43, 0.17, 0.19);
  cam::ClOptions o;
  o.max_tile_bytes = spec.nx * 9 * 37 + 5;  // several tiles
  const cam::ClEngine e(m, cam::Cutter::ball(6), o);
  std::mutex mu;
  double lo = 2, hi = -1;
  std::size_t tiles = 0;
  e.compute_tiles(spec, [&](const cam::ClTile&) { ++tiles; }, [&](double f) {
    std::lock_guard<std::mutex> l(mu);
    lo = std::min(lo, f);
    hi = std::max(hi, f);
  });
  EXPECT_GT(tiles, 3u);
  EXPECT_GE(lo, 0.0);
  EXPECT_LT(lo, 1.0 / double(tiles));  // the first tile reports its own part, not the grid's end
  EXPECT_DOUBLE_EQ(hi, 1.0);

  struct Stop {};
  std::size_t tiles_before_stop = 0;
  EXPECT_THROW(e.compute_tiles(spec, [&](const cam::ClTile&) { ++tiles_before_stop; },
                               [](double f) {
                                 if (f > 0.5) throw Stop{};
                               }),
               Stop);
  EXPECT_LT(tiles_before_stop, tiles);
}
