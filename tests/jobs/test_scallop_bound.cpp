// The finishing's scallop bound, measured by cutting: the steep-and-shallow
// finishing at a scallop height H (rows spaced by the slope across them,
// waterlines on the steep ground) machined into a height map with the
// simulator's own removal leaves at most H above what the ball can reach at
// all (its reach limit: the ball on every node of a dense CL lattice), plus
// the path's tolerance -- on level ground, the rounded border, the bead and
// around the letters' walls.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <vector>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/deviation.hpp"
#include "cncstream/cam/path_machining.hpp"
#include "cncstream/cam/reach.hpp"
#include "cncstream/geometry/stl.hpp"
#include "cncstream/jobs/toolpath_job.hpp"
#include "jobs_test_util.hpp"

using namespace cncstream;

namespace {

// The pieces as the program cuts them: between two pieces up to `top`,
// across, and down (machine_path joins consecutive pieces straight).
std::vector<cam::Polyline> joined_over(const std::vector<cam::Polyline>& pieces, double top) {
  std::vector<cam::Polyline> out;
  for (const cam::Polyline& pl : pieces) {
    if (pl.empty()) continue;
    if (!out.empty()) {
      const geometry::Vec3 a = out.back().back(), b = pl.front();
      out.push_back({{a.x, a.y, top}, {b.x, b.y, top}});
    }
    out.push_back(pl);
  }
  return out;
}

void expect_scallop_bound(const char* cutter) {
  SCOPED_TRACE(cutter);
  jobs::ToolpathParams p;
  p.part.stl = jobstest::plaque();
  p.cutter = cam::parse_cutter_spec(cutter);
  p.strategy = jobs::FinishStrategy::SteepShallow;
  p.scallop = 0.05;
  p.tolerance = 0.01;
  // The top-left corner: the rounded border, the bead's corner and legs,
  // the "C" (walls facing every way) and level ground between them.
  p.bounds = cam::XYBounds{-1.6, 55, 34, 101.6};
  const jobs::ToolpathProgram r = jobs::generate_toolpath(p);
  ASSERT_GT(r.waterline_pieces, 0u);
  // Rows over level ground farther apart than over the slopes.
  EXPECT_GT(r.path.stepover, r.path.stepover_min * 1.3);

  const geometry::Mesh mesh = geometry::load_stl(jobstest::plaque()).mesh;
  const double top = mesh.bounds().hi.z + 2;
  // Inside the window by more than the ball's radius: no edge effects.
  const cam::GridSpec sim = cam::GridSpec::covering(1.0131, 57.0173, 31.6, 99.6, 0.05, 0.05);
  const std::vector<double> machined =
      cam::machine_path(sim, std::vector<double>(sim.size(), top), joined_over(r.finish_pieces, top), p.cutter);
  const cam::ClEngine engine(mesh, p.cutter);
  const double R = p.cutter.radius;
  const cam::ClGrid dense = engine.compute(cam::reach_lattice(sim, sim.x0 - R, sim.y0 - R, sim.x1() + R, sim.y1() + R, 0.05, 0.05));
  const std::vector<double> reach = cam::reach_heights(dense, p.cutter, sim, std::vector<std::uint8_t>(sim.size(), 1));

  // The part's own surface (off it, beside the plate's outer wall, the
  // ball cannot reach the floor's corner and there is no part to finish).
  // The reach lattice cannot follow a CL that drops like a cliff (a ball
  // beside a vertical wall): nodes steeper than 80 degrees do not count.
  const cam::DesignHeights design = cam::design_heights(mesh, sim);
  // A scallop is measured across the surface: a vertical height times the
  // cosine of the part's slope there (NaN: not counted).
  auto across = [&](std::size_t i, std::size_t j) {
    const double none = std::numeric_limits<double>::quiet_NaN();
    if (i == 0 || j == 0 || i + 1 == sim.nx || j + 1 == sim.ny) return none;
    const std::size_t k = j * sim.nx + i;
    const double zx0 = design.z[k - 1], zx1 = design.z[k + 1], zy0 = design.z[k - sim.nx], zy1 = design.z[k + sim.nx];
    if (design.off_part[k] || !std::isfinite(zx0 + zx1 + zy0 + zy1 + reach[k])) return none;
    const double slope = std::atan(std::hypot(zx1 - zx0, zy1 - zy0) / (2 * sim.dx));
    return slope < 80 * std::numbers::pi / 180 ? std::cos(slope) : none;
  };
  double worst = -HUGE_VAL, sum = 0, gouge = 0;
  std::size_t n = 0, over = 0, worst_k = 0, gouge_k = 0;
  for (std::size_t j = 0; j < sim.ny; ++j)
    for (std::size_t i = 0; i < sim.nx; ++i) {
      const std::size_t k = j * sim.nx + i;
      if (!design.off_part[k] && design.z[k] - machined[k] > gouge) {
        gouge = design.z[k] - machined[k];
        gouge_k = k;
      }
      const double c = across(i, j);
      if (!std::isfinite(c)) continue;
      const double left = (machined[k] - reach[k]) * c;
      sum += left;
      ++n;
      if (left > *p.scallop) ++over;
      if (left > worst) {
        worst = left;
        worst_k = k;
      }
    }
  ASSERT_GT(n, sim.size() * 8 / 10);
  const double wx = sim.x(worst_k % sim.nx), wy = sim.y(worst_k / sim.nx);
  std::printf("scallop: max %.4f mm at X%.2f Y%.2f, mean %.4f mm, %zu of %zu nodes above %.3f mm; %zu rows %.3f to "
              "%.3f mm apart\n",
              worst, wx, wy, sum / double(n), over, n, *p.scallop, r.path.rows.size(), r.path.stepover_min,
              r.path.stepover);
  // The tolerance: merged points and arcs ride up to it above the CL.
  EXPECT_LE(worst, *p.scallop + p.tolerance) << "at X" << wx << " Y" << wy << ": machined " << machined[worst_k]
                                             << ", reach " << reach[worst_k] << ", cl " << engine.height_at(wx, wy);
  // And nowhere below the part (the G-code's half-micron rounding aside).
  EXPECT_LT(gouge, 2e-3) << "at X" << sim.x(gouge_k % sim.nx) << " Y" << sim.y(gouge_k / sim.nx);
}

}  // namespace

TEST(ScallopBound, SteepShallowFinishingLeavesAtMostTheScallopHeight) { expect_scallop_bound("ball:3.175"); }

// A sign maker's tapered ball: its scallops grow from its 0.5 mm tip, and its
// waterline levels are spaced by the walls they cut.
TEST(ScallopBound, TaperedBallLeavesAtMostTheScallopHeight) { expect_scallop_bound("taper:1:5:3.175"); }
