// Where to resume when the operator does not say: the line the machine was
// last seen cutting, or a planner queue before the last `ok`.
#include <gtest/gtest.h>

#include <string>

#include "cncstream/gcode/program.hpp"
#include "cncstream/gcode/resume.hpp"

using cncstream::geometry::Vec3;
using cncstream::gcode::choose_resume_line;
using cncstream::gcode::LastSeen;
using cncstream::gcode::trace_program;

namespace {

// Line 1 sets modes; line k (2..41) moves from X=k-2 to X=k-1 at Y0 Z-1.
std::string straight_program() {
  std::string t = "G21 G90 G1 Z-1 F500\n";
  for (int k = 2; k <= 41; ++k) t.append("X").append(std::to_string(k - 1)).append("\n");
  return t;
}

}  // namespace

TEST(ResumeChoice, TheLineThroughTheLastReportedPosition) {
  const auto trace = trace_program(straight_program());
  // Seen at X=27.5 (on line 29, from X27 to X28) when line 38 had been answered.
  const auto c = choose_resume_line(trace, 40, LastSeen{{27.5, 0, -1}, 38});
  EXPECT_EQ(c.after_line, 28u) << c.reason;
  EXPECT_NE(c.reason.find("on line 29"), std::string::npos) << c.reason;
}

TEST(ResumeChoice, AtAJointTheEarlierLineIsRunAgain) {
  const auto trace = trace_program(straight_program());
  // X=30 is the end of line 31 and the start of line 32.
  EXPECT_EQ(choose_resume_line(trace, 40, LastSeen{{30, 0, -1}, 40}).after_line, 30u);
}

TEST(ResumeChoice, OnAPathThatCrossesItselfTheEarliestQueuedPassWins) {
  // Out along Y=0 to X10, over to Y=1, back, and down through (5, 0) again.
  const std::string t = "G21 G90 G1 Z-1 F500\nX10\nY1\nX5\nY0\nY-1\nX0\n";
  const auto trace = trace_program(t);
  // (5, 0) lies on line 2 (X0 -> X10) and on line 6 (Y1 -> Y-1 at X5).
  EXPECT_EQ(choose_resume_line(trace, 7, LastSeen{{5, 0, -1}, 7}).after_line, 1u);
}

TEST(ResumeChoice, WithoutAReportItBacksOffOnePlannerQueue) {
  const auto trace = trace_program(straight_program());
  const auto c = choose_resume_line(trace, 40, std::nullopt);
  EXPECT_EQ(c.after_line, 40u - 16u) << c.reason;
  EXPECT_NE(c.reason.find("no position report"), std::string::npos);
  // Never before the first motion line.
  EXPECT_EQ(choose_resume_line(trace, 5, std::nullopt).after_line, 0u);
}

TEST(ResumeChoice, APositionOutsideTheQueuedLinesIsNotTrusted) {
  const auto trace = trace_program(straight_program());
  // X=3.5 is on line 5, but with line 38 answered the planner held lines 23..38 at most.
  const auto stale = choose_resume_line(trace, 40, LastSeen{{3.5, 0, -1}, 38});
  EXPECT_EQ(stale.after_line, 24u) << stale.reason;
  EXPECT_NE(stale.reason.find("none of the lines"), std::string::npos) << stale.reason;
  // Off the path altogether (e.g. reported in other units).
  EXPECT_EQ(choose_resume_line(trace, 40, LastSeen{{27.5, 3, -1}, 38}).after_line, 24u);
}
