#include <gtest/gtest.h>

#include <cmath>

#include "cncstream/gcode/motion_planner.hpp"
#include "cncstream/gcode/program.hpp"

using namespace cncstream;
using namespace cncstream::gcode;

TEST(Program, TraceAndErrors) {
  const std::string prog =
      "%\n(header)\nG21 G90\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10\nM6\nG2 X20 Y0 I5 J0\nG0 Z5\n%\n";
  ProgramTrace t = trace_program(prog);
  ASSERT_EQ(t.errors.size(), 1u);
  EXPECT_EQ(t.errors[0].line, 6u);
  EXPECT_EQ(t.errors[0].status, 20);
  EXPECT_NE(t.errors[0].message().find("line 7: error:20"), std::string::npos);
  ASSERT_GT(t.segments.size(), 5u);
  EXPECT_EQ(t.segments.back().to, (geometry::Vec3{20, 0, 5}));
  EXPECT_EQ(t.segments.front().source_line, 3u);
}

TEST(Program, StateBeforeLineForResume) {
  const std::string prog = "G20\nG91\nG1 X1 F10\nM3 S500\nG90 X0\n";
  ParserState s = state_before_line(prog, 4);
  EXPECT_TRUE(s.modal.inches);
  EXPECT_TRUE(s.modal.incremental);
  EXPECT_EQ(s.modal.spindle, SpindleState::CW);
  EXPECT_NEAR(s.position.x, 25.4, 1e-12);
  EXPECT_NEAR(s.feed_rate, 254, 1e-9);
}

TEST(Program, WorkCoordinates) {
  ProgramTrace t = trace_program("G10 L2 P1 X100\nG0 X1\n");
  ASSERT_EQ(t.segments.size(), 1u);
  EXPECT_NEAR(t.segments[0].to.x, 101, 1e-12);
  EXPECT_NEAR(t.segments[0].work_to().x, 1, 1e-12);
}

TEST(MotionPlanner, SingleMoveTrapezoidTime) {
  MotionLimits lim;
  lim.max_rate = {6000, 6000, 6000};
  lim.acceleration = {100, 100, 100};
  // 100 mm at 60 mm/s, a = 100: accel 0.6 s over 18 mm, cruise 64 mm, decel 0.6 s.
  const double t = estimate_motion_time({{{0, 0, 0}, {100, 0, 0}, 3600, false, 0, 0}}, lim);
  EXPECT_NEAR(t, 0.6 + 64.0 / 60 + 0.6, 1e-9);
  // Triangle: 1 mm never reaches 60 mm/s: t = 2*sqrt(d/a).
  const double t2 = estimate_motion_time({{{0, 0, 0}, {1, 0, 0}, 3600, false, 0, 0}}, lim);
  EXPECT_NEAR(t2, 2 * std::sqrt(2 * 0.5 / 100), 1e-9);
}

TEST(MotionPlanner, JunctionsAndLookahead) {
  MotionLimits lim;
  lim.max_rate = {6000, 6000, 6000};
  lim.acceleration = {100, 100, 100};
  std::vector<MotionBlock> straight, corner;
  for (int i = 0; i < 100; ++i) {
    if (i < 50) straight.push_back({{i * 2.0, 0, 0}, {i * 2.0 + 2, 0, 0}, 3600, false, 0, 0});
    const geometry::Vec3 a = (i % 2) ? geometry::Vec3{1, 0, 0} : geometry::Vec3{0, 0, 0};
    const geometry::Vec3 b = (i % 2) ? geometry::Vec3{0, 0, 0} : geometry::Vec3{1, 0, 0};
    corner.push_back({a + geometry::Vec3{0, i * 1.0, 0}, b + geometry::Vec3{0, i + 1.0, 0}, 3600, false, 0, 0});
  }
  const double ts = estimate_motion_time(straight, lim);
  EXPECT_NEAR(ts, 0.6 + 64.0 / 60 + 0.6, 1e-6);  // collinear pieces plan like one move
  // With 1 mm pieces 15 blocks of look-ahead cannot stop from 60 mm/s (18 mm):
  // the planner caps the speed, as on the firmware.
  std::vector<MotionBlock> fine;
  for (int i = 0; i < 100; ++i) fine.push_back({{i * 1.0, 0, 0}, {i + 1.0, 0, 0}, 3600, false, 0, 0});
  EXPECT_GT(estimate_motion_time(fine, lim), ts + 0.05);
  const double tc = estimate_motion_time(corner, lim);
  EXPECT_GT(tc, ts * 1.2);  // zig-zag slows at each junction
  lim.junction_deviation = 0.1;
  EXPECT_LT(estimate_motion_time(corner, lim), tc);
  lim.acceleration = {1000, 1000, 1000};
  EXPECT_LT(estimate_motion_time(corner, lim), tc);
}

TEST(MotionPlanner, AdvanceInPiecesMatchesEstimateAndHolds) {
  MotionLimits lim;
  lim.max_rate = {6000, 6000, 6000};
  lim.acceleration = {100, 100, 100};
  MotionQueue q(lim);
  q.push({{0, 0, 0}, {100, 0, 0}, 3600, false, 0, 0});
  double t = 0, travelled = 0;
  while (!q.empty()) {
    auto r = q.advance(0.013, [&](const geometry::Vec3& a, const geometry::Vec3& b, const MotionBlock&) { travelled += norm(b - a); });
    t += r.time;
  }
  EXPECT_NEAR(t, 0.6 + 64.0 / 60 + 0.6, 1e-6);
  EXPECT_NEAR(travelled, 100, 1e-9);
  // Hold at full speed: stops within v^2/2a = 18 mm, then resumes to the end.
  q.push({{100, 0, 0}, {0, 0, 0}, 3600, false, 0, 0});
  q.advance(1.0);
  const double x_before = q.position().x;
  q.hold();
  q.advance(10.0);
  EXPECT_TRUE(q.at_rest());
  EXPECT_NEAR(x_before - q.position().x, 18, 1e-6);
  q.resume();
  while (!q.empty()) q.advance(0.1);
  EXPECT_NEAR(q.position().x, 0, 1e-12);
}
