// The reach limit and the split of material left into scallop and material
// no stepover removes: a brute-force check of reach_heights() on aligned and
// unaligned grids, and a slot narrower than the cutter, whose depth below the
// cutter's bridging height must not be reported as scallop.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "cam/cl_test_meshes.hpp"
#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/deviation.hpp"
#include "cncstream/cam/path_machining.hpp"
#include "cncstream/cam/raster.hpp"
#include "cncstream/cam/reach.hpp"
#include "cncstream/cam/thread_limit.hpp"
#include "cncstream/cam/scallop.hpp"

using namespace cncstream;

namespace {

// min over CL nodes within R of CL + profile, by looking at every node.
double brute_reach(const cam::ClGrid& cl, const cam::Cutter& c, double x, double y) {
  double best = HUGE_VAL;
  for (std::size_t j = 0; j < cl.spec.ny; ++j)
    for (std::size_t i = 0; i < cl.spec.nx; ++i) {
      const double d = std::hypot(cl.spec.x(i) - x, cl.spec.y(j) - y);
      if (d <= c.radius * (1 + 1e-12)) best = std::min(best, cl.at(i, j) + c.profile_height(d));
    }
  return best;
}

void expect_brute(const cam::GridSpec& at, const cam::Cutter& c, const cam::ClGrid& cl) {
  std::vector<std::uint8_t> wanted(at.size(), 1);
  wanted[3] = 0;
  std::vector<double> reach;
  cam::run_with_thread_limit(2, [&] { reach = cam::reach_heights(cl, c, at, wanted); });
  ASSERT_EQ(reach.size(), at.size());
  EXPECT_TRUE(std::isnan(reach[3]));
  for (std::size_t k = 0; k < at.size(); ++k) {
    if (!wanted[k]) continue;
    const double want = brute_reach(cl, c, at.x(k % at.nx), at.y(k / at.nx));
    if (std::isinf(want))
      EXPECT_TRUE(std::isinf(reach[k])) << k;
    else
      EXPECT_NEAR(reach[k], want, 1e-9) << "node " << k;
  }
}

// A land at z = 0 with a slot of width w and depth D along x, centred on y = 0.
geometry::Mesh slot(double w, double depth) {
  geometry::Mesh m;
  auto add = [&m](const geometry::Mesh& b) {
    const auto base = static_cast<std::uint32_t>(m.vertices.size());
    m.vertices.insert(m.vertices.end(), b.vertices.begin(), b.vertices.end());
    for (auto t : b.triangles) m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  };
  add(cl_test::box({-12, -12, -5}, {12, 12, -depth}));
  add(cl_test::box({-12, -12, -depth}, {12, -w / 2, 0}));
  add(cl_test::box({-12, w / 2, -depth}, {12, 12, 0}));
  return m;
}

}  // namespace

TEST(Reach, MatchesBruteForceOnAlignedAndUnalignedGrids) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> z(-1, 1);
  for (const cam::Cutter& c : {cam::Cutter::ball(2), cam::Cutter::flat(1.5), cam::Cutter::bull(2, 0.3)}) {
    SCOPED_TRACE(c.spec());
    const cam::GridSpec at_aligned = cam::GridSpec::covering(0, 0, 3, 2, 0.4, 0.05);
    const cam::GridSpec lat = cam::reach_lattice(at_aligned, -1.5, -1.5, 4.5, 3.5, 0.14, 0.14);
    // Every node of `at` on the lattice or halfway between (two stamps).
    EXPECT_NEAR(lat.dx, 0.4 / 3, 1e-12);
    EXPECT_NEAR(lat.dy, 0.1, 1e-12);
    cam::ClGrid cl;
    cl.spec = lat;
    for (std::size_t k = 0; k < lat.size(); ++k) cl.z.push_back(z(rng));
    expect_brute(at_aligned, c, cl);
    // Nodes at arbitrary offsets: more offsets than stamps are kept for.
    const cam::GridSpec at_loose = cam::GridSpec::covering(0.013, -0.021, 2.9, 2.1, 0.0371, 0.0913);
    expect_brute(at_loose, c, cl);
  }
}

TEST(Reach, SlotNarrowerThanTheCutterIsUnreachableNotScallop) {
  const double w = 2, depth = 2, s = 0.5;
  const geometry::Mesh part = slot(w, depth);
  const cam::GridSpec sim = cam::GridSpec::covering(-6, -6, 6, 6, 0.1, s / 10);
  const cam::DesignHeights design = cam::design_heights(part, sim);
  for (const cam::Cutter& cut : {cam::Cutter::ball(6), cam::Cutter::bull(6, 1)}) {
    SCOPED_TRACE(cut.spec());
    const cam::ClEngine e(part, cut);
    cam::RasterOptions o;
    o.stepover = s;
    o.step = 0.1;
    const cam::RasterPath path = cam::build_raster(e, {-10, -10, 10, 10}, o);
    const auto machined = cam::machine_path(sim, std::vector<double>(sim.size(), 3.0), cam::raster_pieces(path), cut);
    std::vector<double> rows;
    for (const auto& r : path.rows) rows.push_back(r.front().y);

    const cam::ClGrid dense = e.compute(cam::reach_lattice(sim, -10, -10, 10, 10, 0.1, 0.1));
    std::vector<std::uint8_t> wanted(sim.size());
    for (std::size_t k = 0; k < sim.size(); ++k) wanted[k] = !design.off_part[k];
    const std::vector<double> reach = cam::reach_heights(dense, cut, sim, wanted);
    const cam::ScallopMap whole = cam::scallops_from_cut(sim, machined, design, rows, true);
    const cam::ScallopMap split = cam::scallops_from_cut(sim, machined, design, rows, true, &reach);

    // The cutter bridges the slot, touching its edges: nothing of the slot
    // is cut at its walls' feet; at its centre a ball sags
    // R - sqrt(R^2 - (w/2)^2) into it, the bull-nose's flat core (radius
    // 2 > w/2) not at all.
    EXPECT_FALSE(whole.unreachable_stats.computed);
    EXPECT_NEAR(whole.stats.max, depth, 0.05);  // without the split the slot counts as scallop
    ASSERT_TRUE(split.unreachable_stats.computed);
    EXPECT_NEAR(split.unreachable_stats.max, depth, 0.05);
    EXPECT_LT(std::fabs(split.unreachable_stats.max_y), w / 2);
    const double sag = cut.type == cam::CutterType::Ball ? 3 - std::sqrt(9 - 1) : 0.0;
    const std::size_t centre = std::size_t(std::lround((0 - sim.y0) / sim.dy)) * sim.nx + std::size_t(std::lround((0 - sim.x0) / sim.dx));
    EXPECT_NEAR(split.unreachable[centre], depth - sag, 1e-3);
    EXPECT_NEAR(split.residual[centre], depth - sag, 1e-3);
    // Scallop is what the flat lands leave between passes; in the slot none.
    const double land = cut.type == cam::CutterType::Ball ? 3 - std::sqrt(9 - s * s / 4) : 0.0;
    EXPECT_LT(split.stats.max, land + 0.01);
    EXPECT_GT(split.stats.max, land - 2e-3);
    EXPECT_LT(split.stats.min, 1e-3);
    // The slot is 2 mm of the 12 mm wide window: about a sixth of the part.
    EXPECT_NEAR(split.unreachable_stats.share, w / 12, 0.03);
    // Residual = scallop part + unreachable part, node by node.
    for (std::size_t k = 0; k < sim.size(); ++k)
      if (std::isfinite(split.residual[k])) {
        ASSERT_GE(split.unreachable[k], 0.0);
        ASSERT_LE(split.unreachable[k], split.residual[k] + 1e-12);
      }
  }
}
