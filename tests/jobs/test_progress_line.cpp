#include <gtest/gtest.h>
#include <cmath>

#include "cncstream/jobs/progress_line.hpp"

using cncstream::jobs::progress_line;
using cncstream::jobs::ProgressPacer;

TEST(ProgressLine, StagePercentAndElapsed) {
  EXPECT_EQ(progress_line("load", 0, 0), "load    0 %  0:00 elapsed");
  EXPECT_EQ(progress_line("tool path", 0.427, 12.4), "tool path   42 %  0:12 elapsed, about 0:17 left");
  EXPECT_EQ(progress_line("done", 1, 75), "done  100 %  1:15 elapsed");
  EXPECT_EQ(progress_line("x", 0.5, 3725), "x   50 %  1:02:05 elapsed, about 1:02:05 left");
}

TEST(ProgressLine, NoGuessOfTimeLeftTooEarly) {
  EXPECT_EQ(progress_line("a", 0.01, 30), "a    1 %  0:30 elapsed");   // under 2 % of the job
  EXPECT_EQ(progress_line("a", 0.5, 0.4), "a   50 %  0:00 elapsed");   // under a second
}

TEST(ProgressLine, FractionsOutOfRangeAreClamped) {
  EXPECT_EQ(progress_line("a", -0.5, 0), "a    0 %  0:00 elapsed");
  EXPECT_EQ(progress_line("a", 1.7, 0), "a  100 %  0:00 elapsed");
  EXPECT_EQ(progress_line("a", std::nan(""), 0), "a    0 %  0:00 elapsed");
}

TEST(ProgressPacer, AtMostTenRedrawsASecondButFirstAndLastAlways) {
  ProgressPacer p;
  EXPECT_TRUE(p.should_draw(0.0, 0.0));    // the first
  EXPECT_FALSE(p.should_draw(0.05, 0.1));  // 50 ms later
  EXPECT_FALSE(p.should_draw(0.099, 0.2));
  EXPECT_TRUE(p.should_draw(0.1, 0.3));
  EXPECT_FALSE(p.should_draw(0.15, 0.4));
  EXPECT_TRUE(p.should_draw(0.16, 1.0));  // the end is always drawn
  int drawn = 0;
  for (int i = 0; i < 1000; ++i) drawn += p.should_draw(1.0 + i * 0.001, 0.5) ? 1 : 0;  // a second of reports
  EXPECT_EQ(drawn, 10);
}

TEST(ProgressPacer, DrawsAtOnceAfterAReset) {
  ProgressPacer p;
  EXPECT_TRUE(p.should_draw(0.0, 0.1));
  EXPECT_FALSE(p.should_draw(0.01, 0.2));
  p.reset();  // the line was cleared for other output
  EXPECT_TRUE(p.should_draw(0.02, 0.2));
}
