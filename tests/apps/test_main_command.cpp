// The operator's main command end to end: STL -> plan (roughing, tool
// change, finishing) -> stream to the built-in simulator (strict RX buffer)
// -> verify the cut.
#include <gtest/gtest.h>

#include "app_run.hpp"
#include "cncstream/transport/journal.hpp"

using namespace apptest;

TEST(MainCommand, PlaqueToTheBuiltInSimulatorCutsWithoutGouge) {
  // The shop's job: rough the block with a 6 mm flat, change to the ball,
  // finish. The simulator's operator mounts the ball when the session asks.
  const auto r = run_cncstream({plaque(), "sim", "--tool", "ball:3.175", "--rough", "flat:6", "--stepover", "2",
                                "--tolerance", "0.02", "--sim-resolution", "0.2", "--yes"});
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("stock in work coordinates: X -1 .. 121, Y -1 .. 101, Z -10.5 .. 1")) << r.out;
  EXPECT_TRUE(r.has("1. roughing   T1 flat:6")) << r.out;
  // The flat does not fit between the letters' strokes: the ball roughs
  // there before it finishes, one tool change for both.
  EXPECT_TRUE(r.has("2. rest roughing T2 ball:3.175")) << r.out;
  EXPECT_TRUE(r.has("3. finishing  T2 ball:3.175")) << r.out;
  EXPECT_TRUE(r.has("roughing first with the flat:6")) << r.out;
  EXPECT_TRUE(r.has("estimated machining time:")) << r.out;
  // The tool change is the session's (the M0 never reaches the controller):
  // measured on the simulator's touch plate, the operator mounting T2.
  EXPECT_FALSE(r.has("PAUSED at line")) << r.out;
  EXPECT_TRUE(r.has("TOOL CHANGE for rest roughing: mount T2, 3.175 mm ball-nose end mill")) << r.out;
  EXPECT_TRUE(r.has("(simulator: the operator mounts T2 and confirms)")) << r.out;
  EXPECT_TRUE(r.has("tool change: T2 measured +0.000 mm from T1 (plate)")) << r.out;
  EXPECT_TRUE(r.has("outcome: completed")) << r.out;
  EXPECT_TRUE(r.has(" 0 RX bytes dropped")) << r.out;
  // Every line answered: the program ends retracted above the stock at the last row's end.
  EXPECT_TRUE(r.has("final position MPos 121.587,101.587,6.000")) << r.out;
  EXPECT_TRUE(r.has(": 0 gouged,")) << r.out;
  // Not even below tolerance: the path's XY are printed exactly and steps
  // beside walls are crossed by staircases.
  EXPECT_TRUE(r.has("no gouge: the machined surface is nowhere below the design")) << r.out;
}

TEST(MainCommand, StlWithoutATerminalOrYesIsRefused) {
  // Finishing alone: the refusal comes after the plan, which need not be long.
  const auto r = run_cncstream({plaque(), "sim", "--tool", "ball:3.175", "--stepover", "3", "--stock", "none"});
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_TRUE(r.has("pass --yes")) << r.out;
  EXPECT_FALSE(r.has("outcome:")) << r.out;
}

TEST(MainCommand, StlWithoutAToolSaysSo) {
  const auto r = run_cncstream({plaque(), "sim", "--yes"});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("--tool")) << r.out;
}

TEST(MainCommand, SubcommandsStillWork) {
  const auto info = run_cncstream({"info", plaque()});
  EXPECT_EQ(info.code, 0) << info.out;
  EXPECT_TRUE(info.has("plaque.stl")) << info.out;
  const auto jobs = run_cncstream({"jobs", "--journal", (temp_dir() / "none.sqlite").string()});
  EXPECT_EQ(jobs.code, 0) << jobs.out;
  const auto bad = run_cncstream({"no-such-file.nc", "sim"});
  EXPECT_NE(bad.code, 0);
  EXPECT_TRUE(bad.has("no-such-file.nc")) << bad.out;
}

namespace {
// Removes the per-process temp folder (journals, programs, logs) at the end.
struct TempCleanup : ::testing::Environment {
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(temp_dir(), ec);
  }
};
const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new TempCleanup);
}  // namespace

// GRBL answers `ok` when a move is planned, not when it is done: a job is
// complete only once the controller reports Idle, with the last move run out.
TEST(MainCommand, CompletionWaitsForTheMachineToStop) {
  const auto prog = temp_dir() / "long_moves.nc";
  {
    std::ofstream f(prog);
    f << "G21 G90 G94\nG1 X40 F500\nG1 X0 Y10\n";  // 9.6 s of motion at 500 mm/min, 1.9 s at --sim-speed 5
  }
  const auto r = run_cncstream({prog.string(), "sim", "--yes", "--sim-speed", "5", "-v"});
  ASSERT_EQ(r.code, 0) << r.out;
  const auto waiting = r.out.find("waiting for the machine to finish its moves");
  const auto done = r.out.find("completed: all 3 lines answered and the machine is idle");
  ASSERT_NE(waiting, std::string::npos) << r.out;
  ASSERT_NE(done, std::string::npos) << r.out;
  // While it waited the machine was still moving, and it ended where the program ends.
  const auto moving = r.out.find("status: Run", waiting);
  EXPECT_LT(moving, done) << r.out;
  EXPECT_TRUE(r.has("| completed | Idle |")) << r.out;
  EXPECT_TRUE(r.has("final position MPos 0.000,10.000,0.000")) << r.out;
}
