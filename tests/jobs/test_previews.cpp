// Preview data of a job: the CL grid resampled small, a program's cutting
// moves rasterised, the path thinned for drawing, and the tool path job
// keeping the first and letting go of the full grid.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "../cam/cl_test_meshes.hpp"
#include "cncstream/cam/cutter.hpp"
#include "cncstream/gcode/program.hpp"
#include "cncstream/jobs/height_preview.hpp"
#include "cncstream/jobs/path_preview.hpp"
#include "cncstream/jobs/toolpath_job.hpp"

using namespace cncstream;
using namespace cncstream::jobs;

namespace {

double dome(double x, double y) { return 2 - ((x - 10) * (x - 10) + (y - 10) * (y - 10)) / 50; }

// Rows along X over [0, 20]^2, 1 mm apart, points every 0.5 mm on the dome,
// joined at the row ends; rapids in (from the origin) and out (far away).
std::string dome_program() {
  std::string g = "G21 G90\nG0 Z5\nG0 X0 Y0\n";
  char b[96];
  std::snprintf(b, sizeof b, "G1 Z%.4f F300\n", dome(0, 0));
  g += b;
  for (int r = 0; r <= 20; ++r) {
    const double y = r;
    if (r > 0) {
      std::snprintf(b, sizeof b, "G1 Y%.4f Z%.4f F1000\n", y, dome(r % 2 ? 20 : 0, y));
      g += b;
    }
    for (int k = 1; k <= 40; ++k) {
      const double x = r % 2 ? 20 - 0.5 * k : 0.5 * k;
      std::snprintf(b, sizeof b, "G1 X%.4f Z%.4f\n", x, dome(x, y));
      g += b;
    }
  }
  return g + "G0 Z5\nG0 X-30 Y-30\nM2\n";
}

std::size_t count_points(const std::vector<std::vector<geometry::Vec3>>& lines) {
  std::size_t n = 0;
  for (const auto& l : lines) n += l.size();
  return n;
}

}  // namespace

TEST(HeightPreview, GridResampledOverTheRowsKeepsTheHighestNode) {
  cam::ClGrid g;
  g.spec = cam::GridSpec{0, 0, 0.1, 0.5, 301, 41};  // 30 x 20 mm
  g.z.resize(g.spec.size());
  for (std::size_t j = 0; j < g.spec.ny; ++j)
    for (std::size_t i = 0; i < g.spec.nx; ++i)
      g.at(i, j) = 5 - (std::pow(g.spec.x(i) - 15, 2) + std::pow(g.spec.y(j) - 10, 2)) / 20;
  // The rows reach a shorter last row at y = 20.3 the grid lacks.
  const cam::XYBounds extent{0, 0, 30, 20.3};
  const geometry::Vec3 offset{-15, -10, -5};
  const auto h = height_preview_from_grid(g, extent, offset, 100);
  EXPECT_EQ(h.grid.nx, 100u);  // 301 nodes across: resampled to the cap
  EXPECT_EQ(h.grid.ny, 42u);   // 0.5 mm apart: as fine as the grid, never finer
  const cam::XYBounds b = h.bounds();
  EXPECT_NEAR(b.x0, -15, 1e-9);
  EXPECT_NEAR(b.y0, -10, 1e-9);
  EXPECT_NEAR(b.x1, 15, 1e-9);
  EXPECT_NEAR(b.y1, 10.3, 1e-9);
  EXPECT_DOUBLE_EQ(h.z_max, 0);  // the apex, 5 mm, moved down by 5
  EXPECT_DOUBLE_EQ(h.z_min, 5 - (225 + 100) / 20.0 - 5);
  // A node keeps the highest grid node under it: the apex survives.
  EXPECT_FLOAT_EQ(*std::max_element(h.z.begin(), h.z.end()), 0.0f);
  // Past the grid's last row: the nearest row's heights.
  for (std::size_t i = 0; i < h.grid.nx; ++i) EXPECT_FLOAT_EQ(h.z[41 * h.grid.nx + i], h.z[40 * h.grid.nx + i]);
}

TEST(HeightPreview, ProgramRasterisedFromItsCutsNotItsRapids) {
  const auto trace = gcode::trace_program(dome_program());
  const auto h = height_preview_from_trace(trace, 256);
  ASSERT_FALSE(h.empty());
  const cam::XYBounds b = h.bounds();  // the cuts' extent; the rapid to (-30, -30) is not in it
  EXPECT_NEAR(b.x0, 0, 1e-9);
  EXPECT_NEAR(b.y0, 0, 1e-9);
  EXPECT_NEAR(b.x1, 20, 1e-9);
  EXPECT_NEAR(b.y1, 20, 1e-9);
  EXPECT_LE(std::max(h.grid.nx, h.grid.ny), 256u);
  // A node keeps the lowest tip in its cell: the top within a node's slope.
  EXPECT_NEAR(h.z_max, 2, 2e-3);
  EXPECT_NEAR(h.z_min, dome(0, 0), 1e-4);
  // Between the rows, grown: nothing left empty; the centre is the top.
  EXPECT_TRUE(std::none_of(h.z.begin(), h.z.end(), [](float z) { return std::isnan(z); }));
  const auto at = [&](double x, double y) {
    const auto i = static_cast<std::size_t>(std::lround((x - b.x0) / h.grid.dx));
    const auto j = static_cast<std::size_t>(std::lround((y - b.y0) / h.grid.dy));
    return h.z[j * h.grid.nx + i];
  };
  EXPECT_NEAR(at(10, 10), 2, 2e-3);
  EXPECT_LT(at(5, 10), at(10, 10));
  EXPECT_LT(at(10, 15), at(10, 10));
  // The picture: long side as asked, square bounds give a square.
  const image::RgbImage img = render_height_preview(h, 64, {0, 0, 0});
  EXPECT_EQ(img.width(), 64);
  EXPECT_EQ(img.height(), 64);
  EXPECT_EQ(img.get(32, 32), image::colormap_viridis(std::clamp((at(10, 10) - h.z_min) / (h.z_max - h.z_min), 0.0, 1.0)));
}

TEST(HeightPreview, APlungeCountsByItsBottomAndRapidsAloneGiveNothing) {
  const auto h = height_preview_from_trace(gcode::trace_program("G0 X5 Y5 Z10\nG1 Z-2 F100\nG1 X15 Z-1\n"), 64);
  ASSERT_FALSE(h.empty());
  EXPECT_NEAR(h.z_min, -2, 1e-6);
  EXPECT_NEAR(h.z_max, -1, 0.01);  // not the plunge's top at 10
  EXPECT_TRUE(height_preview_from_trace(gcode::trace_program("G0 X5 Y5\nG0 Z3\n")).empty());
  EXPECT_THROW(render_height_preview(HeightPreview{}, 64, {}), std::invalid_argument);
}

TEST(PathPreview, ThinnedToTheBudgetKeepingEndsAndKinds) {
  const auto trace = gcode::trace_program(dome_program());
  const geometry::Vec3 first = trace.segments.front().work_from(), last = trace.segments.back().work_to();
  const auto all = decimate_path(trace, 1000000);
  EXPECT_EQ(all.points, all.total_points + 2);  // the rapid-to-cut and cut-to-rapid corners count twice
  EXPECT_EQ(all.cuts.size(), 1u);
  EXPECT_EQ(all.rapids.size(), 2u);
  for (std::size_t budget : {2000u, 200u, 50u, 7u, 2u}) {
    const auto p = decimate_path(trace, budget);
    EXPECT_EQ(p.total_points, all.total_points);
    EXPECT_LE(p.points, budget) << budget;
    EXPECT_EQ(count_points(p.cuts) + count_points(p.rapids), p.points);
    // With two points the one span holds cuts: a cut; with more, rapids begin and end the path.
    const geometry::Vec3 a = p.rapids.empty() ? p.cuts.front().front() : p.rapids.front().front();
    EXPECT_EQ(a, first) << budget;
    const geometry::Vec3 z = p.rapids.empty() ? p.cuts.back().back() : p.rapids.back().back();
    EXPECT_EQ(z, last) << budget;
    if (budget >= 7) {
      EXPECT_EQ(p.cuts.size(), 1u) << budget;
      EXPECT_EQ(p.rapids.size(), 2u) << budget;
    }
  }
  // With room for a few hundred points, the row ends (the corners) are kept.
  const auto p = decimate_path(trace, 200);
  std::size_t at_ends = 0;
  for (const auto& q : p.cuts.front()) at_ends += (std::abs(q.x) < 1e-9 || std::abs(q.x - 20) < 1e-9);
  EXPECT_GE(at_ends, 42u);  // 21 rows, both ends
  EXPECT_THROW(decimate_path(trace, 1), std::invalid_argument);
}

TEST(PathPreview, AJumpOfTheWorkOffsetIsNotDrawnAcross) {
  const auto p = decimate_path(gcode::trace_program("G1 X10 F100\nG92 X0\nG1 X5\n"), 100);
  ASSERT_EQ(p.cuts.size(), 2u);
  EXPECT_EQ(p.cuts[0].back(), (geometry::Vec3{10, 0, 0}));
  EXPECT_EQ(p.cuts[1].front(), (geometry::Vec3{0, 0, 0}));
  EXPECT_EQ(p.cuts[1].back(), (geometry::Vec3{5, 0, 0}));
  EXPECT_TRUE(p.rapids.empty());
  EXPECT_EQ(decimate_path(gcode::trace_program("G21\n"), 100).points, 0u);
}

TEST(ToolpathJob, KeepsASmallHeightPreviewOfItsClGridInWorkCoordinates) {
  ToolpathParams p;
  p.part.mesh = std::make_shared<const geometry::Mesh>(cl_test::dome_on_plate(20, 8));
  p.part.stl = "dome";
  p.cutter = cam::parse_cutter_spec("ball:3");
  p.stepover = 1;
  const auto r = generate_toolpath(p);
  EXPECT_TRUE(r.path.grid.z.empty());  // the full grid is not kept
  ASSERT_FALSE(r.preview.empty());
  EXPECT_LE(std::max(r.preview.grid.nx, r.preview.grid.ny), kPreviewSideMax);
  const cam::XYBounds b = r.preview.bounds();
  EXPECT_NEAR(b.x0, r.path.bounds.x0 + r.work_offset.x, 1e-9);
  EXPECT_NEAR(b.y0, r.path.bounds.y0 + r.work_offset.y, 1e-9);
  EXPECT_NEAR(b.x1, r.path.bounds.x1 + r.work_offset.x, 1e-9);
  EXPECT_NEAR(b.y1, r.path.bounds.y1 + r.work_offset.y, 1e-9);
  // The program's cuts reach the same box and heights.
  const auto trace = gcode::trace_program(r.gcode);
  double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9, zmax = -1e9;
  for (const auto& s : trace.segments) {
    if (s.rapid) continue;
    const bool along = s.from.x != s.to.x || s.from.y != s.to.y;  // a plunge's top is no cut
    for (const geometry::Vec3& q : {s.work_from(), s.work_to()}) {
      x0 = std::min(x0, q.x);
      x1 = std::max(x1, q.x);
      y0 = std::min(y0, q.y);
      y1 = std::max(y1, q.y);
      if (along) zmax = std::max(zmax, q.z);
    }
  }
  EXPECT_NEAR(x0, b.x0, 1e-3);
  EXPECT_NEAR(x1, b.x1, 1e-3);
  EXPECT_NEAR(y0, b.y0, 1e-3);
  EXPECT_NEAR(y1, b.y1, 1e-3);
  EXPECT_NEAR(zmax, r.preview.z_max, 0.01);
  // The dome's centre (10, 10 in the model) is the highest node.
  const auto& g = r.preview.grid;
  const double cx = 10 + r.work_offset.x, cy = 10 + r.work_offset.y;
  const auto i = static_cast<std::size_t>(std::lround((cx - g.x0) / g.dx));
  const auto j = static_cast<std::size_t>(std::lround((cy - g.y0) / g.dy));
  EXPECT_NEAR(r.preview.z[j * g.nx + i], r.preview.z_max, 0.05);
}
