// G-code -> the viewer's segments through the project's interpreter: arcs
// are chords whose ends lie on the circle, rapids are flagged, modal state,
// offsets, errors and operations as the firmware and CAM programs mean them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "cncstream/image/category_map.hpp"
#include "cncstream/viewer/toolpath_buffers.hpp"

using namespace cncstream;
using namespace cncstream::viewer;

namespace {

image::Rgb colour_of(const Toolpath& p, std::size_t segment) {
  const PathVertex& v = p.vertices[p.segments[segment].vertex];
  return {v.r, v.g, v.b};
}

}  // namespace

TEST(ViewerToolpath, ArcsAreSampledOnTheCircle) {
  // A quarter circle of radius 10 about the origin, clockwise from +X to -Y.
  const Toolpath p = build_toolpath("G21 G90 G17\nG0 X10 Y0 Z-1\nG2 X0 Y-10 I-10 J0 F500\n");
  ASSERT_GE(p.size(), 12u);  // 0.002 mm chord error on r = 10: dozens of chords
  EXPECT_EQ(p.arcs, 1u);
  EXPECT_TRUE(p.rapid(0));
  for (std::size_t k = 1; k < p.size(); ++k) {
    EXPECT_FALSE(p.rapid(k));
    EXPECT_EQ(p.segments[k].line, 2u);
    EXPECT_FLOAT_EQ(p.segments[k].feed, 500);
    for (const geometry::Vec3& q : {p.from(k), p.to(k)}) {
      EXPECT_NEAR(std::hypot(q.x, q.y), 10, 1e-5);
      EXPECT_NEAR(q.z, -1, 1e-6);
      EXPECT_LE(q.x, 10 + 1e-5);
      EXPECT_LE(q.y, 1e-5);  // clockwise from +X goes through -Y, never +Y
    }
    // Each chord's middle is about the arc tolerance inside the circle
    // (GRBL's chord count is an approximation: a few percent over).
    const geometry::Vec3 m = (p.from(k) + p.to(k)) * 0.5;
    EXPECT_LE(10 - std::hypot(m.x, m.y), 0.002 * 1.05);
  }
  const geometry::Vec3 end = p.to(p.size() - 1);
  EXPECT_NEAR(end.x, 0, 1e-6);
  EXPECT_NEAR(end.y, -10, 1e-6);
}

TEST(ViewerToolpath, ArcsInTheXzPlane) {
  const Toolpath p = build_toolpath("G18 G0 X5 Y2 Z0\nG3 X-5 Z0 I-5 K0 F100\n", {0.01, {}, {}});
  ASSERT_GT(p.size(), 4u);
  for (std::size_t k = 1; k < p.size(); ++k) {
    const geometry::Vec3 q = p.to(k);
    EXPECT_NEAR(std::hypot(q.x, q.z), 5, 1e-5);
    EXPECT_NEAR(q.y, 2, 1e-6);
  }
}

TEST(ViewerToolpath, RapidsAreFlaggedAndDashedAlongTheirRun) {
  const Toolpath p = build_toolpath("G0 Z5\nG0 X3 Y4\nG1 Z0 F100\nG1 X10 F400\nG0 Z5\n");
  ASSERT_EQ(p.size(), 5u);
  EXPECT_EQ(p.rapids, 3u);
  EXPECT_TRUE(p.rapid(0));
  EXPECT_TRUE(p.rapid(1));
  EXPECT_FALSE(p.rapid(2));
  EXPECT_FALSE(p.rapid(3));
  EXPECT_TRUE(p.rapid(4));
  EXPECT_EQ(p.segments[0].feed, 0);
  EXPECT_FLOAT_EQ(p.segments[3].feed, 400);
  // One strip: each segment ends where the next begins.
  ASSERT_EQ(p.vertices.size(), 6u);
  for (std::size_t k = 0; k < p.size(); ++k) EXPECT_EQ(p.segments[k].vertex, k + 1);
  // The dash pattern continues from the first rapid into the second...
  EXPECT_FLOAT_EQ(p.vertices[1].along, 5);
  EXPECT_FLOAT_EQ(p.vertices[2].along, 10);
  // ...and starts again after a cut.
  EXPECT_FLOAT_EQ(p.vertices[4].along, 0);
  EXPECT_FLOAT_EQ(p.vertices[5].along, 5);
  EXPECT_EQ(p.min_feed, 100);
  EXPECT_EQ(p.max_feed, 400);
  // Colours: rapids orange, cuts on the feed ramp.
  EXPECT_EQ(colour_of(p, 0), kRapidColour);
  EXPECT_EQ(colour_of(p, 2), image::colormap_viridis(0));
  EXPECT_EQ(colour_of(p, 3), image::colormap_viridis(1));
  EXPECT_EQ(colour_of(p, 4), kRapidColour);
}

TEST(ViewerToolpath, ModalStateAndWorkOffsetsAreTheInterpreters) {
  // Incremental moves accumulate; G92 makes the current point X0, and the
  // viewer draws work coordinates; the offset option shifts everything.
  ToolpathOptions o;
  o.offset = {100, 0, 0};
  const Toolpath p = build_toolpath("G91 G1 X1 F100\nX1\nX1\nG90\nG92 X0\nG1 X2\n", o);
  ASSERT_EQ(p.size(), 4u);
  EXPECT_NEAR(p.to(2).x, 103, 1e-6);
  EXPECT_NEAR(p.from(3).x, 100, 1e-6);  // X3 machine is X0 in work coordinates
  EXPECT_NEAR(p.to(3).x, 102, 1e-6);
  EXPECT_FLOAT_EQ(p.segments[1].feed, 100);  // F is modal
  // The strip jumps, hidden, from X103 to X100.
  ASSERT_EQ(p.vertices.size(), 6u);
  EXPECT_EQ(p.vertices[p.segments[3].vertex - 1].kind, kJump);
  EXPECT_EQ(p.vertices[p.segments[3].vertex].kind, kCut);
}

TEST(ViewerToolpath, RejectedLinesAreRecordedAndSkipped) {
  const Toolpath p = build_toolpath("G1 X1 F100\nG1 X\nG5 X3\nG1 X2\n");
  ASSERT_EQ(p.errors.size(), 2u);
  EXPECT_EQ(p.errors[0].line, 1u);
  EXPECT_EQ(p.errors[1].line, 2u);
  EXPECT_NE(p.errors[1].status, 0);
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p.segments[1].line, 3u);
}

TEST(ViewerToolpath, OperationsBeginAtNamesAndToolChanges) {
  const std::string program =
      "(Roughing)\n(T1 flat 6 mm)\nT1\nG0 Z5\nG1 Z0 F100\nG1 X10\n"
      "(Finishing)\nG1 Y10\nG1 X0\n"
      "T2\nG1 Y0\n";
  Toolpath p = build_toolpath(program);
  ASSERT_EQ(p.operations.size(), 3u);
  EXPECT_EQ(p.operations[0], "Roughing");
  EXPECT_EQ(p.operations[1], "Finishing");
  EXPECT_EQ(p.operations[2], "operation 3");
  ASSERT_EQ(p.size(), 6u);
  EXPECT_EQ(p.segments[2].operation, 0u);
  EXPECT_EQ(p.segments[3].operation, 1u);
  EXPECT_EQ(p.segments[4].operation, 1u);
  EXPECT_EQ(p.segments[5].operation, 2u);
  colour_toolpath(p, PathColouring::Operation);
  for (std::size_t k = 1; k < p.size(); ++k)
    EXPECT_EQ(colour_of(p, k), image::category_colour(p.segments[k].operation));
  EXPECT_THROW(parse_path_colouring("speed"), std::invalid_argument);
}

TEST(ViewerToolpath, PointAtFollowsTheTimeline) {
  const Toolpath p = build_toolpath("G0 X0 Y0 Z0\nG1 X10 F100\nG1 Y10\n");
  ASSERT_EQ(p.size(), 2u);  // the first rapid goes nowhere
  EXPECT_NEAR(p.point_at(0.5).x, 5, 1e-6);
  EXPECT_NEAR(p.point_at(1.25).y, 2.5, 1e-6);
  EXPECT_NEAR(p.point_at(7).y, 10, 1e-6);
  EXPECT_NEAR(p.point_at(-1).x, 0, 1e-6);
}

TEST(ViewerToolpath, TimelineCountsTheStripsVertices) {
  const Toolpath p = build_toolpath("G1 X1 F100\nG92 X0\nG1 X1\nG1 X2\n");
  ASSERT_EQ(p.size(), 3u);
  EXPECT_EQ(p.vertices_done(0), 0u);
  EXPECT_EQ(p.vertices_done(1), 2u);    // vertices 0, 1: the first segment
  EXPECT_EQ(p.vertices_done(2.5), 4u);  // past the hidden jump
  EXPECT_EQ(p.vertices_done(99), 5u);
}

TEST(ViewerToolpath, DistantStripDropsOnlyWhatCannotBeSeen) {
  // A wavy cut, 0.05 mm steps, then a rapid along the same line.
  Toolpath p;
  geometry::Vec3 at{0, 0, 0};
  for (int k = 1; k <= 2000; ++k) {
    const geometry::Vec3 next{k * 0.05, 0, 0.3 * std::sin(k * 0.05)};
    append_segment(p, at, next, false, 1000, 0, 0);
    at = next;
  }
  append_segment(p, at, at + geometry::Vec3{10, 0, 0}, true, 0, 1, 0);
  append_segment(p, at + geometry::Vec3{10, 0, 0}, at + geometry::Vec3{20, 0, 0}, true, 0, 2, 0);
  colour_toolpath(p, PathColouring::Feed);
  const double tol = 0.01;
  const auto keep = display_strip(p, tol);
  ASSERT_GE(keep.size(), 3u);
  EXPECT_LT(keep.size(), p.vertices.size() / 4);
  EXPECT_EQ(keep.front(), 0u);
  EXPECT_EQ(keep.back(), p.vertices.size() - 1);
  // The vertex where the cut turns into the rapid is kept.
  EXPECT_NE(std::find(keep.begin(), keep.end(), p.segments[1999].vertex), keep.end());
  for (std::size_t q = 0; q + 1 < keep.size(); ++q) {
    const PathVertex &a = p.vertices[keep[q]], &b = p.vertices[keep[q + 1]];
    const geometry::Vec3 pa{a.x, a.y, a.z}, pb{b.x, b.y, b.z};
    for (std::uint32_t v = keep[q] + 1; v < keep[q + 1]; ++v) {
      const PathVertex& m = p.vertices[v];
      const geometry::Vec3 pm{m.x, m.y, m.z};
      const geometry::Vec3 ab = pb - pa;
      const double t = std::clamp(dot(pm - pa, ab) / dot(ab, ab), 0.0, 1.0);
      EXPECT_LE(norm(pm - (pa + ab * t)), tol + 1e-6);
      EXPECT_EQ(m.kind, b.kind);  // one kind per merged line
    }
  }
}
