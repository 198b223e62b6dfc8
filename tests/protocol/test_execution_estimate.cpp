#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cncstream/protocol/execution_estimate.hpp"
#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/protocol/grbl_session.hpp"
#include "cncstream/protocol/marlin_session.hpp"

using namespace cncstream::protocol;

TEST(ExecutionEstimate, LinesWithAxisWordsMove) {
  EXPECT_TRUE(line_moves("G1X1F100"));
  EXPECT_TRUE(line_moves("G2X1Y1I0.5J0"));
  EXPECT_TRUE(line_moves("z-1"));
  EXPECT_FALSE(line_moves("G90G21"));
  EXPECT_FALSE(line_moves("M3S18000"));
  EXPECT_FALSE(line_moves("(X is here)G4P1"));
  EXPECT_FALSE(line_moves("F500;X1"));
}

TEST(ExecutionEstimate, PlannerQueueIsTakenOffTheAnsweredMoves) {
  ExecutionEstimate e;
  e.on_answered(1, "G21G90");  // no block
  EXPECT_EQ(e.executing_line(), 1);
  for (long l = 2; l <= 16; ++l) e.on_answered(l, "G1X" + std::to_string(l));
  // 15 moves answered, none reported yet: the first of them runs.
  EXPECT_EQ(e.executing_line(), 2);
  e.on_status(/*free*/ 3, false, 15);  // 12 queued, the running one included
  EXPECT_EQ(e.executing_line(), 16 - 12 + 1);
  e.on_answered(17, "G1X17");  // a new block: the running one is the same
  EXPECT_EQ(e.executing_line(), 5);
  e.on_status(14, false, 15);  // one left: the newest move
  EXPECT_EQ(e.executing_line(), 17);
  e.on_status(15, true, 15);
  EXPECT_EQ(e.executing_line(), 17);
}

TEST(ExecutionEstimate, WithoutBufferReportsARunningPlannerIsFull) {
  ExecutionEstimate e;
  for (long l = 1; l <= 40; ++l) e.on_answered(l, "G1X" + std::to_string(l));
  e.on_status(std::nullopt, false, 15);
  EXPECT_EQ(e.executing_line(), 40 - 15 + 1);
  e.on_status(std::nullopt, true, 15);  // idle: every answered line ran
  EXPECT_EQ(e.executing_line(), 40);
}

TEST(ExecutionEstimate, NeverGoesBackwardsAndResets) {
  ExecutionEstimate e;
  for (long l = 1; l <= 10; ++l) e.on_answered(l, "G1X1");
  e.on_status(15, true, 15);
  EXPECT_EQ(e.executing_line(), 10);
  e.on_status(5, false, 15);  // a stale report
  EXPECT_EQ(e.executing_line(), 10);
  e.reset();
  EXPECT_EQ(e.executing_line(), 0);
}

namespace {
const FirmwareProfile& profile(const char* name) {
  static std::map<std::string, FirmwareProfile> cache;
  auto it = cache.find(name);
  if (it == cache.end())
    it = cache.emplace(name, load_firmware_profile(std::string(CNCSTREAM_SOURCE_DIR "/firmware-profiles/") + name))
             .first;
  return it->second;
}
}  // namespace

// The case the browser test showed: 15 slow moves all enter GRBL's planner
// at once; progress must follow the machine, not the answers.
TEST(ExecutionEstimate, GrblProgressFollowsTheMotionNotTheAnswers) {
  GrblSessionOptions o;
  o.poll_status = false;
  GrblSession s(profile("grbl-1.1.toml"), o);
  std::vector<std::string> lines;
  for (int i = 1; i <= 15; ++i) lines.push_back("G1X" + std::to_string(i * 40) + "F500");
  s.start_job(prepare_program(lines, "slow.nc", 80), JobMode::Run, 0);
  s.take_output();
  for (int i = 0; i < 15; ++i) s.on_bytes("ok\n", 0.01 * i);
  EXPECT_EQ(s.progress().lines_answered, 15u);
  EXPECT_EQ(s.progress().last_answered_line, 15);
  s.on_bytes("<Run|MPos:20,0,0|Bf:0,128|FS:500,0>\n", 1);  // 15 blocks queued: line 1 runs
  EXPECT_EQ(s.progress().executing_line, 1);
  s.on_bytes("<Run|MPos:300,0,0|Bf:8,128|FS:500,0>\n", 40);
  EXPECT_EQ(s.progress().executing_line, 9);
  s.on_bytes("<Idle|MPos:600,0,0|Bf:15,128|FS:0,0>\n", 80);
  EXPECT_EQ(s.progress().executing_line, 15);
}

TEST(ExecutionEstimate, MarlinUsesOkPlannerFree) {
  MarlinSession s(profile("marlin.toml"));
  s.tick(0);
  s.take_output();
  s.on_bytes("ok\n", 0);  // M110's
  std::vector<std::string> lines;
  for (int i = 1; i <= 6; ++i) lines.push_back("G1X" + std::to_string(i) + "F500");
  s.start_job(prepare_program(lines, "slow.nc", 80), JobMode::Run, 0);
  // One line in flight at a time (send_window 1); 16 planner blocks.
  s.on_bytes("ok N1 P15 B3\n", 0.1);
  s.on_bytes("ok N2 P14 B3\n", 0.2);
  s.on_bytes("ok N3 P13 B3\n", 0.3);  // 3 queued: line 1 still runs
  EXPECT_EQ(s.progress().last_answered_line, 3);
  EXPECT_EQ(s.progress().executing_line, 1);
  s.on_bytes("ok N4 P15 B3\n", 5);  // only line 4 left in the planner
  EXPECT_EQ(s.progress().executing_line, 4);
  s.on_bytes("ok N5\n", 6);  // no P: the planner is taken to be full
  EXPECT_EQ(s.progress().executing_line, 4);
  s.on_bytes("ok N6\n", 7);
  EXPECT_EQ(s.progress().outcome, JobOutcome::Completed);
  EXPECT_EQ(s.progress().executing_line, 6);  // completed: everything ran
}
