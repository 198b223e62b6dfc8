// The outline (protocol/outline_trace.hpp) against the simulated GRBL 1.1:
// the traced path is the program's XY extent at the safe height, and a lost
// link leaves at most the segment in flight.
#include <gtest/gtest.h>

#include <algorithm>

#include <cmath>

#include "cncstream/gcode/program_extent.hpp"
#include "cncstream/protocol/outline_trace.hpp"
#include "support/routine_bench.hpp"

using namespace cncstream;
using namespace cncstream::protocol;

namespace {

const std::vector<std::string> kOutlineProgram = {
    "G21 G90", "G0 Z5", "G0 X2 Y3", "G1 Z-1 F300", "G1 X40 Y3", "G3 X40 Y23 I0 J10", "G1 X2 Y23", "G0 Z5", "M2"};

struct OutlineBench : test::RoutineBench {
  struct Move {
    geometry::Vec3 a, b;
    bool rapid;
  };
  std::vector<Move> moves;
  OutlineBench() : RoutineBench(cncsim::MachineOptions{}) {
    command("G10 L2 P1 X100 Y50 Z-20");
    command("G0 X0 Y0 Z1");  // work: below the program's travel height
    m.set_motion_observer([this](const geometry::Vec3& a, const geometry::Vec3& b, bool rapid) { moves.push_back({a, b, rapid}); });
  }
};

}  // namespace

TEST(OutlineTrace, TracesTheProgramsBoxAtTheSafeHeight) {
  const auto extent = gcode::program_extent(kOutlineProgram);
  const OutlineConfig c = outline_from_extent(extent, std::nullopt, 2000, "part.nc", OutlineShape::Box);
  // The arc bulges to X50: the extent is the chorded arc's, as the firmware runs it.
  EXPECT_NEAR(c.x0, 2, 1e-9);
  EXPECT_NEAR(c.x1, 50, 0.01);
  EXPECT_NEAR(c.y0, 3, 1e-9);
  EXPECT_NEAR(c.y1, 23, 1e-9);
  EXPECT_NEAR(c.safe_z, 5, 1e-9);
  OutlineBench b;
  OutlineTraceRoutine r(c);
  b.run(r);
  ASSERT_TRUE(r.succeeded()) << r.failure();
  const geometry::Vec3 wco{100, 50, -20};
  bool corners[4] = {false, false, false, false};
  for (const auto& mv : b.moves) {
    const geometry::Vec3 a = mv.a - wco, e = mv.b - wco;
    if (std::hypot(e.x - a.x, e.y - a.y) < 1e-9) continue;  // the climb
    // Every XY move at the safe height...
    EXPECT_NEAR(a.z, 5, 1e-6);
    EXPECT_NEAR(e.z, 5, 1e-6);
    if (mv.rapid) continue;  // the move to the first corner
    // ...and every traced segment on the box's edge.
    const bool on_x = std::fabs(a.x - e.x) < 1e-6 && (std::fabs(a.x - c.x0) < 1e-6 || std::fabs(a.x - c.x1) < 1e-6);
    const bool on_y = std::fabs(a.y - e.y) < 1e-6 && (std::fabs(a.y - c.y0) < 1e-6 || std::fabs(a.y - c.y1) < 1e-6);
    EXPECT_TRUE(on_x || on_y) << a.x << "," << a.y << " -> " << e.x << "," << e.y;
    for (int k = 0; k < 4; ++k) {
      const double cx = (k == 1 || k == 2) ? c.x1 : c.x0, cy = k >= 2 ? c.y1 : c.y0;
      if (std::hypot(e.x - cx, e.y - cy) < 1e-6) corners[k] = true;
    }
  }
  for (bool k : corners) EXPECT_TRUE(k);
  // Up before any XY move (the first move with XY motion is already at the safe Z: checked above), spindle off.
  EXPECT_TRUE(b.sent_any("M5"));
  EXPECT_TRUE(b.sent_any("G1 X50.000 Y3.000 F2000.000") || b.sent_any("G1 X49.999") || b.sent_any("G1 X50.001"));
}

// The default trace: the hull of the program's moves, corner to corner, at
// the safe height; the box's empty corner (X50 Y3, beside the arc) is never
// visited, and every position the program moves to lies within the
// tolerance of the traced polygon.
TEST(OutlineTrace, TracesTheHullOfTheProgramsMovesByDefault) {
  const auto extent = gcode::program_extent(kOutlineProgram);
  const OutlineConfig c = outline_from_extent(extent, std::nullopt, 2000, "part.nc");
  ASSERT_EQ(c.shape, OutlineShape::Hull);
  ASSERT_GE(c.path.size(), 5u);
  OutlineBench b;
  OutlineTraceRoutine r(c);
  b.run(r);
  ASSERT_TRUE(r.succeeded()) << r.failure();
  EXPECT_NE(r.summary().find("hull"), std::string::npos) << r.summary();
  const geometry::Vec3 wco{100, 50, -20};
  const auto segment_distance = [](const gcode::XyPoint& u, const gcode::XyPoint& v, double x, double y) {
    const double dx = v[0] - u[0], dy = v[1] - u[1];
    const double s = std::clamp(((x - u[0]) * dx + (y - u[1]) * dy) / (dx * dx + dy * dy), 0.0, 1.0);
    return std::hypot(u[0] + s * dx - x, u[1] + s * dy - y);
  };
  std::vector<bool> visited(c.path.size(), false);
  for (const auto& mv : b.moves) {
    const geometry::Vec3 a = mv.a - wco, e = mv.b - wco;
    if (std::hypot(e.x - a.x, e.y - a.y) < 1e-9) continue;  // the climb
    EXPECT_NEAR(a.z, 5, 1e-6);
    EXPECT_NEAR(e.z, 5, 1e-6);
    EXPECT_GT(std::hypot(e.x - 50, e.y - 3), 1.0) << "the box's corner beside the arc";
    if (mv.rapid) continue;  // to the first corner
    // Every traced piece runs along one edge of the hull...
    bool on_edge = false;
    for (std::size_t i = 0; i < c.path.size() && !on_edge; ++i) {
      const auto& u = c.path[i];
      const auto& v = c.path[(i + 1) % c.path.size()];
      on_edge = segment_distance(u, v, a.x, a.y) < 1e-3 && segment_distance(u, v, e.x, e.y) < 1e-3;
    }
    EXPECT_TRUE(on_edge) << a.x << "," << a.y << " -> " << e.x << "," << e.y;
    // ...and reaches its corners.
    for (std::size_t k = 0; k < c.path.size(); ++k)
      if (std::hypot(e.x - c.path[k][0], e.y - c.path[k][1]) < 1e-3) visited[k] = true;
  }
  for (std::size_t k = 0; k < visited.size(); ++k) EXPECT_TRUE(visited[k]) << "corner " << k;
  // The arc's chords (what the program runs) lie within the tolerance of it.
  for (int k = 0; k <= 90; ++k) {
    const double a = -M_PI / 2 + M_PI * k / 90.0;
    const gcode::XyPoint p{40 + 10 * std::cos(a), 13 + 10 * std::sin(a)};
    double inside = 1e300;
    for (std::size_t i = 0; i < c.path.size(); ++i) {
      const auto& u = c.path[i];
      const auto& v = c.path[(i + 1) % c.path.size()];
      inside = std::min(inside, ((v[0] - u[0]) * (p[1] - u[1]) - (v[1] - u[1]) * (p[0] - u[0])) /
                                    std::hypot(v[0] - u[0], v[1] - u[1]));
    }
    EXPECT_GE(inside, -kOutlineHullTolerance - 0.003) << "arc point " << k;
  }
}

TEST(OutlineTrace, ALostLinkLeavesAtMostTheSegmentInFlight) {
  const OutlineConfig c =
      outline_from_extent(gcode::program_extent(kOutlineProgram), 10.0, 2000, "part.nc", OutlineShape::Box);
  OutlineBench b;
  OutlineTraceRoutine r(c);
  std::size_t at_loss = 0;
  b.run(r, 900, [&](double) {
    if (at_loss == 0 && b.sent.size() >= 2 && b.sent.back().rfind("G1 ", 0) == 0 &&
        std::count_if(b.sent.begin(), b.sent.end(), [](const std::string& l) { return l.rfind("G1 ", 0) == 0; }) == 2) {
      r.abort("the controller disconnected");
      at_loss = b.sent.size();
    }
  });
  ASSERT_GT(at_loss, 0u);
  EXPECT_FALSE(r.succeeded());
  EXPECT_EQ(b.sent.size(), at_loss);
  b.m.run_until_idle();
  // It stopped where the second segment ends: (x1, y1), not further.
  const geometry::Vec3 w = b.m.work_position();
  EXPECT_NEAR(w.x, c.x1, 1e-6);
  EXPECT_NEAR(w.y, c.y1, 1e-6);
  EXPECT_NEAR(w.z, 10, 1e-6);
}

TEST(OutlineTrace, RefusesASafeZBelowTheProgramsTravelHeight) {
  const auto extent = gcode::program_extent(kOutlineProgram);
  try {
    outline_from_extent(extent, 2.0, 1000, "part.nc");
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("part.nc"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("5.000"), std::string::npos) << e.what();
  }
  EXPECT_THROW(outline_from_extent(extent, std::nullopt, 0, "part.nc"), std::invalid_argument);
  EXPECT_THROW(outline_from_extent(gcode::program_extent({"G0 Z5"}), std::nullopt, 1000, "z.nc"), std::invalid_argument);
}
