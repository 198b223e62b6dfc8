// Raster finishing: rows, exact CL vertices, no link below the CL surface,
// and G-code that parses back (with our own interpreter) to the same path.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/raster.hpp"
#include "cncstream/gcode/finishing_program.hpp"
#include "cncstream/gcode/program.hpp"
#include "cncstream/geometry/mesh.hpp"

using namespace cncstream;

namespace {

// A closed box [x0,x1]x[y0,y1]x[0,h] with a raised block on top: vertical walls
// and sharp edges are where links are most likely to cut below the CL.
Mesh stepped_part() {
  Mesh m;
  auto box = [&](Vec3 lo, Vec3 hi) {
    const std::uint32_t b = static_cast<std::uint32_t>(m.vertices.size());
    for (int k = 0; k < 8; ++k)
      m.vertices.push_back({k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z});
    const int f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                          {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    for (auto& t : f) m.triangles.push_back({b + t[0], b + t[1], b + t[2]});
  };
  box({0, 0, 0}, {20, 14, 3});
  box({6, 4, 3}, {13, 9, 5.5});
  // A sloped facet pair (a ramp) on the box top: not axis aligned.
  const std::uint32_t b = static_cast<std::uint32_t>(m.vertices.size());
  m.vertices.insert(m.vertices.end(), {{1, 10, 3}, {5, 10, 3}, {1, 13, 4.5}, {5, 13, 4.5}});
  m.triangles.push_back({b, b + 1, b + 2});
  m.triangles.push_back({b + 1, b + 3, b + 2});
  return m;
}

// Largest amount by which a straight move from a to b dips below the CL surface.
double worst_dip(const ClEngine& e, const Vec3& a, const Vec3& b, int samples) {
  double worst = 0;
  for (int k = 0; k <= samples; ++k) {
    const double t = double(k) / samples;
    const Vec3 p = a + (b - a) * t;
    worst = std::max(worst, e.height_at(p.x, p.y) - p.z);
  }
  return worst;
}

}  // namespace

class RasterPerCutter : public ::testing::TestWithParam<const char*> {};

TEST_P(RasterPerCutter, RowsVerticesAndLinksAreGougeFree) {
  const Mesh mesh = stepped_part();
  const Cutter cutter = parse_cutter_spec(GetParam());
  const ClEngine engine(mesh, cutter);
  RasterOptions o;
  o.stepover = 0.7;
  o.step = 0.1;
  const XYBounds b = default_bounds(mesh, cutter);
  const RasterPath path = build_raster(engine, b, o);

  // Rows evenly spread, never wider than asked, alternating direction.
  const std::size_t expect_rows = static_cast<std::size_t>(std::ceil((b.y1 - b.y0) / 0.7 - 1e-9)) + 1;
  ASSERT_EQ(path.rows.size(), expect_rows);
  EXPECT_LE(path.stepover, 0.7 + 1e-12);
  EXPECT_EQ(path.links.size(), path.rows.size() - 1);
  for (std::size_t r = 0; r < path.rows.size(); ++r) {
    const auto& row = path.rows[r];
    ASSERT_GE(row.size(), 2u);
    EXPECT_NEAR(row.front().x, r % 2 ? b.x1 : b.x0, 1e-9);
    EXPECT_NEAR(row.back().x, r % 2 ? b.x0 : b.x1, 1e-9);
    for (const auto& p : row) EXPECT_NEAR(p.y, b.y0 + double(r) * path.stepover, 1e-9);
  }
  EXPECT_LT(path.points_after_merge, path.points_before_merge);

  // Every vertex is an exact CL point; no move dips below the CL surface by
  // more than the accepted chord sag (1e-4 mm) or a sub-micron step nick.
  double worst = 0;
  std::size_t moves = 0;
  for (const auto* set : {&path.rows, &path.links}) {
    for (const auto& pl : *set) {
      for (std::size_t k = 0; k < pl.size(); ++k) {
        EXPECT_NEAR(pl[k].z, engine.height_at(pl[k].x, pl[k].y), 1e-9);
        if (k == 0) continue;
        ++moves;
        // A flat end's CL surface has vertical steps at walls; they are
        // resolved to 1 um-wide moves, which can only nick a wall's side.
        const double du = std::hypot(pl[k].x - pl[k - 1].x, pl[k].y - pl[k - 1].y);
        if (du <= 1e-3 + 1e-9) continue;
        worst = std::max(worst, worst_dip(engine, pl[k - 1], pl[k], 16));
      }
    }
  }
  EXPECT_GT(moves, 100u);
  EXPECT_LE(worst, 1.5e-4) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(Cutters, RasterPerCutter, ::testing::Values("ball:3.175", "bull:6:1", "flat:4"));

TEST(Raster, FlatCutterStepsAreResolvedToAMicron) {
  const Mesh mesh = stepped_part();
  const ClEngine engine(mesh, parse_cutter_spec("flat:4"));
  RasterOptions o;
  o.stepover = 1.0;
  o.step = 0.1;
  const RasterPath path = build_raster(engine, default_bounds(mesh, engine.cutter()), o);
  for (const auto& row : path.rows)
    for (std::size_t k = 1; k < row.size(); ++k) {
      const double du = std::hypot(row[k].x - row[k - 1].x, row[k].y - row[k - 1].y);
      // Any move steeper than 45 degrees is the last micron of a wall step.
      if (std::fabs(row[k].z - row[k - 1].z) > du + 1e-9) EXPECT_LT(du, 1e-3 + 1e-9);
    }
}

TEST(Raster, GcodeParsesBackToThePath) {
  const Mesh mesh = stepped_part();
  const ClEngine engine(mesh, parse_cutter_spec("ball:3.175"));
  RasterOptions o;
  o.stepover = 0.5;
  o.step = 0.1;
  const RasterPath path = build_raster(engine, default_bounds(mesh, engine.cutter()), o);
  const Box3 box = mesh.bounds();
  const Vec3 off = work_offset(box, XYOrigin::PartMin, ZZero::PartTop);
  MachiningParams mp;
  mp.header_comments = {"test part (with parentheses) and a very long comment " + std::string(100, 'x')};
  ProgramStats st;
  const std::string text = finishing_program(path, off, mp, &st);

  // GRBL-safe text.
  std::size_t lines = 0;
  for (auto line : gcode::split_lines(text)) {
    ++lines;
    EXPECT_LE(line.size(), 80u) << line;
    EXPECT_EQ(line.find_first_of("eE"), std::string_view::npos) << line;
  }
  EXPECT_EQ(lines, st.lines);

  const gcode::ProgramTrace trace = gcode::trace_program(text);
  ASSERT_TRUE(trace.errors.empty()) << trace.errors.front().message();
  // Feed moves in order: the path's vertices, placed and rounded (z up).
  std::vector<Vec3> expect;
  for (std::size_t r = 0; r < path.rows.size(); ++r) {
    for (const auto& v : path.rows[r]) expect.push_back(v + off);
    if (r < path.links.size())
      for (const auto& v : path.links[r]) expect.push_back(v + off);
  }
  std::vector<Vec3> got;
  for (const auto& s : trace.segments)
    if (!s.rapid) got.push_back(s.work_to());
  // Consecutive duplicates (row end = link start) are written once.
  std::vector<Vec3> dedup;
  for (const auto& p : expect)
    if (dedup.empty() || std::fabs(dedup.back().x - p.x) > 5e-4 || std::fabs(dedup.back().y - p.y) > 5e-4 ||
        std::fabs(dedup.back().z - p.z) > 1e-3)
      dedup.push_back(p);
  ASSERT_EQ(got.size(), dedup.size());
  for (std::size_t k = 0; k < got.size(); ++k) {
    EXPECT_NEAR(got[k].x, dedup[k].x, 5e-4);
    EXPECT_NEAR(got[k].y, dedup[k].y, 5e-4);
    EXPECT_GE(got[k].z, dedup[k].z - 1e-9);  // rounded up, never down
    EXPECT_LE(got[k].z, dedup[k].z + 1e-3 + 1e-9);
  }
  // Starts and ends above the part at the safe height, spindle on then off.
  EXPECT_NE(text.find("M3 S18000"), std::string::npos);
  EXPECT_NE(text.find("M5\nM2\n"), std::string::npos);
  EXPECT_NEAR(trace.final_state.work_position().z, mp.safe_z, 1e-9);
}

TEST(Raster, SafeZBelowThePathIsRefused) {
  const Mesh mesh = stepped_part();
  const ClEngine engine(mesh, parse_cutter_spec("ball:3"));
  RasterOptions o;
  o.stepover = 2;
  const RasterPath path = build_raster(engine, default_bounds(mesh, engine.cutter()), o);
  MachiningParams mp;
  mp.safe_z = 0.2;  // Z0 at the top: the path reaches 0
  EXPECT_THROW(finishing_program(path, work_offset(mesh.bounds(), XYOrigin::PartMin, ZZero::PartTop), mp),
               std::invalid_argument);
}
