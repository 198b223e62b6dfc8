// The viewer's surfaces, pure: the cutter's mesh lies on its profile, the
// part keeps its facets, a cut is coloured with the deviation map's scale.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "cncstream/image/deviation_map.hpp"
#include "cncstream/viewer/scene.hpp"
#include "cncstream/viewer/scene_mesh.hpp"

using namespace cncstream;
using namespace cncstream::viewer;

namespace {

// A 10 x 10 mm plate's top at z = 1 (two facets).
geometry::Mesh plate() {
  geometry::Mesh m;
  m.vertices = {{0, 0, 1}, {10, 0, 1}, {10, 10, 1}, {0, 10, 1}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

image::Rgb colour(const MeshVertex& v) { return {v.r, v.g, v.b}; }

}  // namespace

TEST(ViewerSceneMesh, CutterLiesOnItsProfile) {
  const geometry::Vec3 tip{12, -3, 4};
  for (const cam::Cutter& c : {cam::Cutter::ball(6), cam::Cutter::flat(3.175), cam::Cutter::bull(8, 1)}) {
    const TriangleMesh m = cutter_surface(c, tip, 20, 24);
    ASSERT_FALSE(m.indices.empty());
    double lowest = 1e9, highest = -1e9;
    for (const MeshVertex& v : m.vertices) {
      const double rho = std::hypot(v.x - tip.x, v.y - tip.y), z = v.z - tip.z;
      EXPECT_LE(rho, c.radius + 1e-5);
      lowest = std::min(lowest, z);
      highest = std::max(highest, z);
      if (z < c.profile_top() - 1e-5) {
        EXPECT_NEAR(z, c.profile_height(std::min(rho, c.radius)), 1e-4) << c.spec();
      }
      EXPECT_NEAR(std::sqrt(v.nx * v.nx + v.ny * v.ny + v.nz * v.nz), 1, 1e-5);
    }
    EXPECT_NEAR(lowest, 0, 1e-6);
    EXPECT_NEAR(highest, 20, 1e-5);
    for (const std::uint32_t i : m.indices) EXPECT_LT(i, m.vertices.size());
  }
  EXPECT_THROW(cutter_surface(cam::Cutter::ball(6), tip, 0, 2), std::invalid_argument);
}

TEST(ViewerSceneMesh, PartKeepsEveryFacet) {
  const TriangleMesh m = part_surface(plate());
  EXPECT_EQ(m.triangles(), 2u);
  EXPECT_EQ(m.vertices.size(), 6u);
  for (const MeshVertex& v : m.vertices) EXPECT_NEAR(std::fabs(v.nz), 1, 1e-6);
  EXPECT_EQ(m.bounds.hi.x, 10);
  EXPECT_EQ(m.bounds.lo.z, 1);
}

TEST(ViewerSceneMesh, CutIsColouredByDeviationWithTheMapsScale) {
  // Nodes every 0.5 mm over 0..12: the plate covers 0..10, the rest is off it.
  cam::GridSpec g;
  g.nx = g.ny = 25;
  g.dx = g.dy = 0.5;
  std::vector<float> z(g.size(), 1.0f);
  const std::size_t gouge = 10 * g.nx + 10, excess = 4 * g.nx + 6, slight = 8 * g.nx + 8;
  z[gouge] = 0.5f;    // 0.5 mm below the design
  z[excess] = 1.3f;   // 0.3 mm above
  z[slight] = 1.02f;  // within 0.05
  z[24 * g.nx + 24] = std::numeric_limits<float>::quiet_NaN();  // no value
  const CutSurface cut = cut_surface(g, z, plate(), 0.05);
  EXPECT_EQ(cut.stats.gouged, 1u);
  EXPECT_EQ(cut.stats.excess, 1u);
  ASSERT_EQ(cut.mesh.vertices.size(), g.size());
  EXPECT_EQ(colour(cut.mesh.vertices[gouge]), image::DeviationPalette::gouge(1));  // the worst gouge: darkest
  EXPECT_EQ(colour(cut.mesh.vertices[excess]), image::DeviationPalette::excess(1));
  EXPECT_EQ(colour(cut.mesh.vertices[slight]), image::DeviationPalette::within);
  EXPECT_EQ(colour(cut.mesh.vertices[2 * g.nx + 3]), image::DeviationPalette::within);
  EXPECT_EQ(colour(cut.mesh.vertices[23 * g.nx + 23]), image::DeviationPalette::off_part);
  const image::DeviationScale scale{0.05, 0.5, 0.3};
  EXPECT_EQ(scale.colour(-0.275), image::DeviationPalette::gouge(0.5));
  // The node without a value leaves out the triangles that touch it.
  EXPECT_EQ(cut.mesh.triangles(), 2u * 24 * 24 - 2);  // the corner cell's two
  EXPECT_THROW(cut_surface(g, std::vector<float>(3, 1.0f), plate(), 0.05), std::invalid_argument);
}

TEST(ViewerScene, TimelineStepsAndTheSlider) {
  Scene s;
  s.program = Toolpath{};
  for (int k = 0; k < 2000; ++k) append_segment(*s.program, {double(k), 0, 0}, {double(k + 1), 0, 0}, false, 100, 0, 0);
  EXPECT_EQ(timeline_step(s, -1), 1996);  // from the end, a 500th back
  s.progress = 1;
  EXPECT_EQ(timeline_step(s, -1), 0);
  EXPECT_EQ(timeline_at_bar(60, 10, 200, 2000), 500);
  EXPECT_EQ(timeline_at_bar(-60, 10, 200, 2000), 0);
  s.cutter = cam::Cutter::ball(2);
  s.progress = 2.5;
  ASSERT_TRUE(s.cutter_tip());
  EXPECT_NEAR(s.cutter_tip()->x, 2.5, 1e-9);
  s.cutter_at = geometry::Vec3{7, 8, 9};
  EXPECT_EQ(s.cutter_tip()->y, 8);
  EXPECT_EQ(format_position({1, -2.5, 0.0004}), "X 1.000 Y -2.500 Z 0.000");
  EXPECT_EQ(format_progress(*s.program, 2.5), "segment 2 of 2000, line 1");
}
