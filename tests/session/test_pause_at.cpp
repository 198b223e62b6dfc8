// Where a job holds on its program's M0: the line after the last answered
// one, past comment lines a streamer may not send.
#include <gtest/gtest.h>

#include "cncstream/session/job_input.hpp"

using cncstream::session::pause_at;

TEST(PauseAt, TheM0AfterTheLastAnsweredLineWithItsNote) {
  const std::vector<std::string> lines = {"G0 Z5", "G1 X10 F1000", "T2", "M0", "G1 X0"};
  const auto p = pause_at(lines, {}, 3);  // T2 answered; GRBL answers the M0 only after cycle start
  ASSERT_TRUE(p);
  EXPECT_EQ(p->line, 4);
  EXPECT_FALSE(pause_at(lines, {}, 1));
  EXPECT_FALSE(pause_at(lines, {}, 5));
}

TEST(PauseAt, CommentLinesBeforeTheM0AreLookedPast) {
  // The comment lines are not sent, so the last answered line is the move.
  const std::vector<std::string> lines = {"G0 Z5", "G1 X10 F1000", "(TOOL CHANGE: mount T2)", "", "(then touch off)",
                                          "M0", "G1 X0"};
  const auto p = pause_at(lines, {}, 2);
  ASSERT_TRUE(p);
  EXPECT_EQ(p->line, 6);
  EXPECT_EQ(p->note, "TOOL CHANGE: mount T2 then touch off");
  // A move after the comments is not a pause.
  EXPECT_FALSE(pause_at({"G1 X1", "(note)", "G1 X2", "M0"}, {}, 1));
}
