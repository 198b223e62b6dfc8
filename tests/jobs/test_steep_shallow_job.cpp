// Steep-and-shallow finishing of the plaque: every move of the finishing
// pieces (waterlines, bridges over the raster's steep stretches, the rows)
// stays on or above the exact CL surface, checked densely along each move
// (within a micron sideways where the CL is a cliff).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/geometry/stl.hpp"
#include "cncstream/jobs/toolpath_job.hpp"
#include "jobs_test_util.hpp"

using namespace cncstream;

TEST(SteepShallowJob, EveryMoveStaysOnOrAboveTheClSurface) {
  jobs::ToolpathParams p;
  p.part.stl = jobstest::plaque();
  p.cutter = cam::parse_cutter_spec("ball:3.175");
  p.stepover = 0.4;
  p.strategy = jobs::FinishStrategy::SteepShallow;
  // The left half: the outer edge, the rim, the "C" and the "S" (walls
  // taller than the ball's radius: cliffs of its CL) in half the time.
  p.bounds = cam::XYBounds{-1.5875, -1.5875, 50, 101.5875};
  const jobs::ToolpathProgram r = jobs::generate_toolpath(p);
  ASSERT_GT(r.waterline_pieces, 0u);
  const geometry::Mesh mesh = geometry::load_stl(jobstest::plaque()).mesh;
  const cam::ClEngine engine(mesh, p.cutter);
  double worst = 0;
  geometry::Vec3 at;
  std::size_t piece_at = 0;
  for (std::size_t k = 0; k < r.finish_pieces.size(); ++k) {
    const cam::Polyline& pl = r.finish_pieces[k];
    for (std::size_t i = 0; i + 1 < pl.size(); ++i) {
      const geometry::Vec3 a = pl[i], b = pl[i + 1];
      const auto n = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(std::hypot(b.x - a.x, b.y - a.y) / 0.02)));
      for (std::size_t s = 0; s <= n; ++s) {
        const geometry::Vec3 q = a + (b - a) * (double(s) / double(n));
        double below = engine.height_at(q.x, q.y) - q.z;
        // Beside a cliff of the CL (a ball's beside a wall taller than its
        // radius) a move a hair into it is far below it: what counts is
        // how far the cutter is sideways into the part, at most a micron
        // here (the G-code's half-micron rounding), as for the raster.
        if (below > 1e-4)
          for (int d = 0; d < 16 && below > 1e-4; ++d) {
            const double ang = d * std::numbers::pi / 8;
            if (engine.height_at(q.x + 1e-3 * std::cos(ang), q.y + 1e-3 * std::sin(ang)) <= q.z + 1e-4) below = 0;
          }
        if (below > worst) {
          worst = below;
          at = q;
          piece_at = k;
        }
      }
    }
  }
  if (worst > 1e-4) {
    const cam::Polyline& pl = r.finish_pieces[piece_at];
    for (std::size_t i = 0; i + 1 < pl.size(); ++i) {
      const geometry::Vec3 a = pl[i], b = pl[i + 1];
      if (std::hypot(a.x - at.x, a.y - at.y) < 3 || std::hypot(b.x - at.x, b.y - at.y) < 3)
        std::printf("%zu: %.4f,%.4f,%.4f (cl %.4f) -> %.4f,%.4f,%.4f\n", i, a.x, a.y, a.z, engine.height_at(a.x, a.y), b.x, b.y, b.z);
    }
  }
  // The raster accepts 1e-4 mm of chord sag between its exact samples.
  EXPECT_LE(worst, 2e-4) << "a move runs " << worst << " mm below the CL at " << at.x << "," << at.y << "," << at.z
                         << " (piece " << piece_at << " of " << r.finish_pieces.size() << ", the first "
                         << r.waterline_pieces << " are waterlines)";
}
