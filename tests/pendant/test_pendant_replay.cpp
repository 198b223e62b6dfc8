// `cncstream pendant sim --replay FILE` end to end: the real program, the
// built-in simulator in real time, a recorded pendant session; the final
// position it prints is where the machine stands.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <regex>

#include "apps/app_run.hpp"
#include "cncstream/pendant/replay_source.hpp"

namespace {

std::string fixture(const std::string& name) {
  return std::string(CNCSTREAM_SOURCE_DIR) + "/tests/pendant/fixtures/" + name;
}

// "MPos: 3.000,-0.200,-9.876" -> the three numbers.
std::optional<std::array<double, 3>> position(const std::string& out, const std::string& label) {
  const std::regex re(label + ": (-?[0-9.]+),(-?[0-9.]+),(-?[0-9.]+)");
  std::smatch m;
  if (!std::regex_search(out, m, re)) return std::nullopt;
  return std::array<double, 3>{std::stod(m[1]), std::stod(m[2]), std::stod(m[3])};
}

}  // namespace

TEST(PendantReplay, StepJogsOnXAndYAndAContinuousZJogEndWhereTheWheelSaid) {
  const auto r = apptest::run_cncstream(
      {"pendant", "sim", "--sim-speed", "1", "--replay", fixture("steps_and_continuous.txt")}, 120);
  ASSERT_EQ(r.code, 0) << r.out;
  const auto m = position(r.out, "MPos");
  ASSERT_TRUE(m) << r.out;
  EXPECT_NEAR((*m)[0], 3.0, 1e-9) << r.out;   // three 1 mm detents
  EXPECT_NEAR((*m)[1], -0.5, 1e-9) << r.out;  // a five-detent spin: every detent counts
  // Continuous -Z for 1.1 s of wheel reports, then the 0.2 s lease: at least
  // the ramp (it reaches 500 mm/min after 3.5 mm), at most full speed for the
  // whole time plus the stop (8.33 mm/s x 1.3 s + 3.5 mm). More would be a jog
  // that ran on after the wheel stopped.
  EXPECT_LT((*m)[2], -3.0) << r.out;
  EXPECT_GT((*m)[2], -14.5) << r.out;
  // The simulator's work offset is zero: WPos is MPos.
  const auto w = position(r.out, "WPos");
  ASSERT_TRUE(w) << r.out;
  EXPECT_NEAR((*w)[2], (*m)[2], 1e-9);
  EXPECT_TRUE(r.has("8 steps sent, 0 dropped, 1 continuous jogs started")) << r.out;
}

TEST(PendantReplay, AnUnplugStopsTheContinuousJogAtOnce) {
  // The same Z jog, but the receiver is pulled 500 ms in, with the wheel still
  // turning in the recording's mind (no report after it) and a lease of 5 s:
  // only the unplug can stop it this early.
  const auto path = apptest::temp_dir() / "unplug.txt";
  std::ofstream(path) << "0 04 00 0e 00 1b 13 00 00\n"
                         "50 04 00 00 00 1b 13 00 00\n"
                         "100 04 00 00 00 1b 13 fc 00\n"
                         "300 04 00 00 00 1b 13 fc 00\n"
                         "500 unplug\n";
  const auto recording = apptest::temp_dir() / "recorded.txt";
  const auto r = apptest::run_cncstream({"pendant", "sim", "--sim-speed", "1", "--lease", "5", "--replay", path.string(),
                                         "--record", recording.string()},
                                        120);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("receiver unplugged")) << r.out;
  const auto m = position(r.out, "MPos");
  ASSERT_TRUE(m) << r.out;
  // 0.4 s of ramp (0.8 mm) and the stop from there (under 1 mm); five
  // seconds of lease would have gone far beyond.
  EXPECT_LT((*m)[2], -0.1) << r.out;
  EXPECT_GT((*m)[2], -3.0) << r.out;

  // --record wrote what the controller received, in the replay format: the
  // connection, the four reports and the unplug, at about their times.
  const auto rec = cncstream::pendant::load_replay(recording);
  ASSERT_EQ(rec.size(), 6u);
  EXPECT_EQ(rec[0].kind, cncstream::pendant::ReplayKind::Plug);
  EXPECT_EQ(rec[1].report, (cncstream::pendant::InputReport{0x04, 0x00, 0x0e, 0x00, 0x1b, 0x13, 0x00, 0x00}));
  EXPECT_EQ(rec[4].report, (cncstream::pendant::InputReport{0x04, 0x00, 0x00, 0x00, 0x1b, 0x13, 0xfc, 0x00}));
  EXPECT_EQ(rec[5].kind, cncstream::pendant::ReplayKind::Unplug);
  EXPECT_NEAR(rec[4].at_ms - rec[1].at_ms, 300, 100);
  EXPECT_NEAR(rec[5].at_ms - rec[1].at_ms, 500, 100);
}

TEST(PendantReplay, ABadReplayFileNamesItsLineBeforeAnyPortOpens) {
  const auto path = apptest::temp_dir() / "bad.txt";
  std::ofstream(path) << "# fine\n0 04 00 00 00 0f 11 00 00\n100 04 00 0g 00 0f 11 00 00\n";
  const auto r = apptest::run_cncstream({"pendant", "/dev/nonexistent-port", "--replay", path.string()});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has(path.string() + ":3: byte 2 '0g' is not a hex byte (00-ff)")) << r.out;
  EXPECT_FALSE(r.has("nonexistent-port")) << r.out;
}

TEST(PendantReplay, EveryDetentCountsWhileAStepJogIsInFlight) {
  // Step 0.1 mm on X; +3 detents, then +2 while the first jog still runs
  // (50 ms later), then +1 and +1 while those run: the jogs queue, nothing
  // is dropped, X ends at the sum (0.7 mm). Then a spin of 100 detents on Y
  // is clamped to 10 steps (1 mm) and said.
  const auto path = apptest::temp_dir() / "detents.txt";
  std::ofstream(path) << "0 04 00 00 00 0f 11 00 00\n"
                         "100 04 00 00 00 0f 11 03 00\n"
                         "150 04 00 00 00 0f 11 02 00\n"
                         "170 04 00 00 00 0f 11 01 00\n"
                         "190 04 00 00 00 0f 11 01 00\n"
                         "1500 04 00 00 00 0f 12 00 00\n"
                         "1600 04 00 00 00 0f 12 64 00\n"
                         "4000 04 00 00 00 0f 12 00 00\n";
  const auto r = apptest::run_cncstream({"pendant", "sim", "--sim-speed", "1", "--replay", path.string()}, 120);
  ASSERT_EQ(r.code, 0) << r.out;
  const auto m = position(r.out, "MPos");
  ASSERT_TRUE(m) << r.out;
  EXPECT_NEAR((*m)[0], 0.7, 1e-9) << r.out;
  EXPECT_NEAR((*m)[1], 1.0, 1e-9) << r.out;
  EXPECT_TRUE(r.has("clamped")) << r.out;
  EXPECT_TRUE(r.has("17 steps sent, 90 dropped")) << r.out;
}
