// Raster finishing: rows, exact CL vertices, no link below the CL surface,
// and G-code that parses back (with our own interpreter) to the same path.
#include <gtest/gtest.h>

#include <sstream>

#include <cmath>
#include <random>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/raster.hpp"
#include "cncstream/gcode/finishing_program.hpp"
#include "cncstream/gcode/gcode_writer.hpp"
#include "cncstream/gcode/program.hpp"
#include "cncstream/geometry/mesh.hpp"

using namespace cncstream;

namespace {

// A closed box [x0,x1]x[y0,y1]x[0,h] with a raised block on top: vertical walls
// and sharp edges are where links are most likely to cut below the CL.
geometry::Mesh stepped_part() {
  geometry::Mesh m;
  auto box = [&](geometry::Vec3 lo, geometry::Vec3 hi) {
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

// How deep a tool-tip point p lies inside the region below the CL surface:
// at most its vertical dip, and at most the horizontal distance to a place
// where the surface is no higher than p (the CL surface has vertical steps
// beside vertical walls, where the dip is sideways).
double penetration(const cam::ClEngine& e, const geometry::Vec3& p) {
  const double vertical = e.height_at(p.x, p.y) - p.z;
  if (vertical <= 0) return 0;
  double best = vertical;
  for (int d = 0; d < 8; ++d) {
    const double a = d * M_PI / 4;
    for (double r = 1e-5; r < best; r *= 1.25)
      if (e.height_at(p.x + r * std::cos(a), p.y + r * std::sin(a)) <= p.z) {
        best = std::min(best, r);
        break;
      }
  }
  return best;
}

// Deepest penetration along a straight move from a to b.
double worst_dip(const cam::ClEngine& e, const geometry::Vec3& a, const geometry::Vec3& b, int samples) {
  double worst = 0;
  for (int k = 0; k <= samples; ++k) worst = std::max(worst, penetration(e, a + (b - a) * (double(k) / samples)));
  return worst;
}

// Every vertex in the band [CL, CL + tolerance] above its exact CL point;
// the deepest dip of any move below the CL surface (rows and links), with
// where it happened.
double worst_path_dip(const cam::ClEngine& engine, const cam::RasterPath& path, double tolerance, std::string* where,
                      std::size_t* moves) {
  double worst = 0;
  for (const auto* set : {&path.rows, &path.links}) {
    for (const auto& pl : *set) {
      for (std::size_t k = 0; k < pl.size(); ++k) {
        // In the band above exact CL points, except the upper corners of
        // staircases across steps narrower than the path resolves: those
        // stand higher, straight over a point next to them.
        const double cl = engine.height_at(pl[k].x, pl[k].y);
        EXPECT_GE(pl[k].z, cl - 1e-6);
        auto same_xy = [&](std::size_t j) { return pl[j].x == pl[k].x && pl[j].y == pl[k].y; };
        if (pl[k].z > cl + tolerance + 1e-6) {
          EXPECT_TRUE((k > 0 && same_xy(k - 1)) || (k + 1 < pl.size() && same_xy(k + 1)));
        }
        if (k == 0) continue;
        ++*moves;
        const double dip = worst_dip(engine, pl[k - 1], pl[k], 16);
        if (dip > worst) {
          worst = dip;
          std::ostringstream o;
          o << "the move from " << pl[k - 1].x << "," << pl[k - 1].y << "," << pl[k - 1].z << " to " << pl[k].x << ","
            << pl[k].y << "," << pl[k].z;
          *where = o.str();
        }
      }
    }
  }
  return worst;
}

}  // namespace

class RasterPerCutter : public ::testing::TestWithParam<const char*> {};

TEST_P(RasterPerCutter, RowsVerticesAndLinksAreGougeFree) {
  const geometry::Mesh mesh = stepped_part();
  const cam::Cutter cutter = cam::parse_cutter_spec(GetParam());
  const cam::ClEngine engine(mesh, cutter);
  cam::RasterOptions o;
  o.stepover = 0.7;
  o.step = 0.1;
  const cam::XYBounds b = cam::default_bounds(mesh, cutter);
  const cam::RasterPath path = cam::build_raster(engine, b, o);

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

  // Every vertex is in the band above its CL point (or a staircase corner); no
  // move dips below the CL surface by more than the accepted chord sag.
  std::string where;
  std::size_t moves = 0;
  const double worst = worst_path_dip(engine, path, o.tolerance, &where, &moves);
  EXPECT_GT(moves, 100u);
  // Steps narrower than 0.1 um are crossed by staircases: only chord sag remains.
  EXPECT_LE(worst, 2e-4) << GetParam() << " on " << where;
}

// With the G-code's decimal lattice every XY is printable exactly, and the
// moves stay gouge-free (a step is resolved to one lattice step at most).
TEST_P(RasterPerCutter, LatticePathIsPrintableAndGougeFree) {
  const geometry::Mesh mesh = stepped_part();
  const cam::Cutter cutter = cam::parse_cutter_spec(GetParam());
  const cam::ClEngine engine(mesh, cutter);
  cam::RasterOptions o;
  o.stepover = 0.7;
  o.step = 0.1;
  o.lattice = cam::XYLattice{0.001, 0.3337, -0.2123};
  const cam::XYBounds b = cam::default_bounds(mesh, cutter);
  const cam::RasterPath path = cam::build_raster(engine, b, o);
  EXPECT_NEAR(path.stepover, 0.7, 1e-12);
  auto on_lattice = [](double v, double origin) {
    const double k = (v - origin) / 0.001;
    return std::fabs(k - std::round(k)) < 1e-6;
  };
  for (const auto* set : {&path.rows, &path.links})
    for (const auto& pl : *set)
      for (const auto& p : pl) {
        ASSERT_TRUE(on_lattice(p.x, 0.3337) && on_lattice(p.y, -0.2123)) << p.x << "," << p.y;
        EXPECT_GE(p.x, b.x0 - 1e-9);
        EXPECT_LE(p.x, b.x1 + 1e-9);
        EXPECT_GE(p.y, b.y0 - 1e-9);
        EXPECT_LE(p.y, b.y1 + 1e-9);
      }
  // The rows cover the bounds to within one lattice step.
  EXPECT_NEAR(path.rows.front().front().y, b.y0, 0.001);
  EXPECT_NEAR(path.rows.back().front().y, b.y1, 0.001);
  for (std::size_t r = 1; r < path.rows.size(); ++r)
    EXPECT_LE(path.rows[r].front().y - path.rows[r - 1].front().y, 0.7 + 1e-9);
  std::string where;
  std::size_t moves = 0;
  const double worst = worst_path_dip(engine, path, o.tolerance, &where, &moves);
  EXPECT_GT(moves, 100u);
  // Steps narrower than one lattice step are crossed by staircases, so only
  // the accepted chord sag remains.
  EXPECT_LE(worst, 2e-4) << GetParam() << " on " << where;
}

INSTANTIATE_TEST_SUITE_P(Cutters, RasterPerCutter, ::testing::Values("ball:3.175", "bull:6:1", "flat:4"));

TEST(Raster, GcodeParsesBackToThePath) {
  const geometry::Mesh mesh = stepped_part();
  const cam::ClEngine engine(mesh, cam::parse_cutter_spec("ball:3.175"));
  cam::RasterOptions o;
  o.stepover = 0.5;
  o.step = 0.1;
  const cam::RasterPath path = cam::build_raster(engine, cam::default_bounds(mesh, engine.cutter()), o);
  const geometry::Box3 box = mesh.bounds();
  const geometry::Vec3 off = work_offset(box, XYOrigin::PartMin, ZZero::PartTop);
  MachiningParams mp;
  mp.header_comments = {"test part (with parentheses) and a very long comment " + std::string(100, 'x')};
  ProgramStats st;
  const std::string text = finishing_program(path, off, mp, &st);

  // GRBL-safe text.
  std::size_t lines = 0;
  for (auto line : gcode::split_lines(text)) {
    ++lines;
    EXPECT_LE(line.size(), 80u) << line;
    if (!line.empty() && line.front() != '(') {
      EXPECT_EQ(line.find_first_of("eE"), std::string_view::npos) << line;
    }
  }
  EXPECT_EQ(lines, st.lines);

  const gcode::ProgramTrace trace = gcode::trace_program(text);
  ASSERT_TRUE(trace.errors.empty()) << trace.errors.front().message();
  // Feed moves in order: the path's vertices, placed and rounded (z up).
  std::vector<geometry::Vec3> expect;
  for (std::size_t r = 0; r < path.rows.size(); ++r) {
    for (const auto& v : path.rows[r]) expect.push_back(v + off);
    if (r < path.links.size())
      for (const auto& v : path.links[r]) expect.push_back(v + off);
  }
  std::vector<geometry::Vec3> got;
  for (const auto& s : trace.segments)
    if (!s.rapid) got.push_back(s.work_to());
  // As written: 3 decimals, z rounded up; repeats of the same written point
  // (row end = link start, sub-resolution steps) are one line.
  std::vector<geometry::Vec3> dedup;
  for (const auto& p : expect) {
    const geometry::Vec3 q{std::stod(format_gcode_number(p.x)), std::stod(format_gcode_number(p.y)), std::ceil(p.z * 1000 - 1e-6) / 1000};
    if (dedup.empty() || !(dedup.back() == q)) dedup.push_back(q);
  }
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
  const geometry::Mesh mesh = stepped_part();
  const cam::ClEngine engine(mesh, cam::parse_cutter_spec("ball:3"));
  cam::RasterOptions o;
  o.stepover = 2;
  const cam::RasterPath path = cam::build_raster(engine, cam::default_bounds(mesh, engine.cutter()), o);
  MachiningParams mp;
  mp.safe_z = 0.2;  // Z0 at the top: the path reaches 0
  const geometry::Vec3 off = work_offset(mesh.bounds(), XYOrigin::PartMin, ZZero::PartTop);
  EXPECT_THROW(finishing_program(path, off, mp), std::invalid_argument);
  // A feed that would print as F0 (GRBL: error 22) is refused too.
  mp.safe_z = 5;
  EXPECT_NO_THROW(finishing_program(path, off, mp));
  mp.plunge_feed = 0.00001;
  EXPECT_THROW(finishing_program(path, off, mp), std::invalid_argument);
}
