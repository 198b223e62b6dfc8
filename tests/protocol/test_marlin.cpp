#include <gtest/gtest.h>

#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/protocol/marlin_session.hpp"

using namespace cncstream::protocol;

namespace {
const FirmwareProfile& marlin() {
  static const auto p = load_firmware_profile(CNCSTREAM_SOURCE_DIR "/firmware-profiles/marlin.toml");
  return p;
}
PreparedProgram program(const std::vector<std::string>& lines) {
  CleanOptions o;
  o.strip_whitespace = false;
  o.reject_realtime_chars = false;
  return prepare_program(lines, "t.gcode", marlin().line_length_limit, o);
}
}  // namespace

TEST(Marlin, Checksum) {
  // XOR of "N1 G28" = 'N'^'1'^' '^'G'^'2'^'8'
  int x = 'N' ^ '1' ^ ' ' ^ 'G' ^ '2' ^ '8';
  EXPECT_EQ(marlin_checksum("N1 G28"), x);
  EXPECT_EQ(marlin_frame(1, "G28"), "N1 G28*" + std::to_string(x));
}

TEST(Marlin, SendResponseOneAtATime) {
  MarlinSession s(marlin());
  s.tick(0);
  EXPECT_EQ(s.take_output(), "M110 N0\n");
  s.start_job(program({"G21", "G1 X10 F600 ; cut", "", "G1 Y5"}), JobMode::Run, 0);
  EXPECT_EQ(s.take_output(), "");  // waits for the M110 ok
  s.on_bytes("ok\n", 0.1);
  EXPECT_EQ(s.take_output(), marlin_frame(1, "G21") + "\n");
  s.on_bytes("ok N1 P15 B3\n", 0.2);
  EXPECT_EQ(*s.planner_free(), 15);
  EXPECT_EQ(s.take_output(), marlin_frame(2, "G1 X10 F600") + "\n");
  s.on_bytes("echo:busy: processing\nok\n", 0.3);
  EXPECT_EQ(s.take_output(), marlin_frame(3, "G1 Y5") + "\n");
  s.on_bytes("ok\n", 0.4);
  EXPECT_EQ(s.progress().outcome, JobOutcome::Completed);
  EXPECT_DOUBLE_EQ(s.modal().feed_rate, 600);
}

TEST(Marlin, ForcedResendGoesBackToTheRequestedLine) {
  MarlinSession s(marlin());
  s.tick(0);
  s.take_output();
  s.on_bytes("ok\n", 0);
  s.start_job(program({"G1 X1", "G1 X2", "G1 X3"}), JobMode::Run, 0);
  EXPECT_EQ(s.take_output(), marlin_frame(1, "G1 X1") + "\n");
  s.on_bytes("ok\n", 1);
  EXPECT_EQ(s.take_output(), marlin_frame(2, "G1 X2") + "\n");
  // Line 2 arrived corrupted.
  s.on_bytes("Error:checksum mismatch, Last Line: 1\nResend: 2\n", 2);
  EXPECT_EQ(s.take_output(), "");  // wait for the ok that follows
  s.on_bytes("ok\n", 2.1);
  EXPECT_EQ(s.take_output(), marlin_frame(2, "G1 X2") + "\n");
  EXPECT_EQ(s.progress().lines_answered, 1u);
  s.on_bytes("ok\n", 3);
  EXPECT_EQ(s.take_output(), marlin_frame(3, "G1 X3") + "\n");
  s.on_bytes("ok\n", 4);
  EXPECT_EQ(s.progress().outcome, JobOutcome::Completed);
  EXPECT_EQ(s.resends(), 1u);
  EXPECT_EQ(s.next_line_number(), 4);
}

TEST(Marlin, FatalErrorEndsJobAndStopDrains) {
  MarlinSession s(marlin());
  s.tick(0);
  s.on_bytes("ok\n", 0);
  s.start_job(program({"G1 X1", "G1 X2"}), JobMode::Run, 0);
  s.take_events();
  s.on_bytes("Error:Printer halted. kill() called!\n", 1);
  EXPECT_EQ(s.progress().outcome, JobOutcome::Error);
  bool explained = false;
  for (const auto& e : s.take_events())
    if (e.kind == EventKind::Alarm && e.info && e.info->position_lost &&
        e.text.find("reset the board") != std::string::npos)
      explained = true;
  EXPECT_TRUE(explained) << "a Marlin error gets its meaning and advice from the profile";
  MarlinSession t(marlin());
  t.tick(0);
  t.on_bytes("ok\n", 0);
  t.start_job(program({"G1 X1", "G1 X2"}), JobMode::Run, 0);
  t.take_output();
  t.stop();
  EXPECT_EQ(t.progress().state, JobState::Stopping);
  t.on_bytes("ok\n", 1);  // line 1 answered: then M410, numbered like any line
  EXPECT_EQ(t.take_output(), marlin_frame(2, "M410") + "\n");
  EXPECT_EQ(t.progress().state, JobState::Stopping);
  t.on_bytes("ok\n", 1.1);
  EXPECT_EQ(t.progress().outcome, JobOutcome::Stopped);
  EXPECT_EQ(t.progress().last_answered_line, 1);
  EXPECT_THROW(t.start_job(program({"G1 X1"}), JobMode::Check, 2), std::invalid_argument);
}

TEST(Marlin, JogsAreRelativeMovesAndReleaseIsAQuickStop) {
  MarlinSession s(marlin());
  s.tick(0);
  s.take_output();
  s.on_bytes("ok\n", 0);  // M110
  ASSERT_EQ(s.jog_step(JogDirection{{1, 0, 0}}, 2.5, 600, 0), "");
  EXPECT_EQ(s.take_output(), marlin_frame(1, "G91") + "\n");
  s.on_bytes("ok\n", 0.1);
  EXPECT_EQ(s.take_output(), marlin_frame(2, "G1X2.500F600") + "\n");
  s.on_bytes("ok\n", 0.2);
  EXPECT_EQ(s.take_output(), marlin_frame(3, "G90") + "\n");
  s.on_bytes("ok\n", 0.3);

  // Continuous: each increment is G91, a relative G1, G90 (Marlin acts on
  // one G-code a line), one line in flight (this profile's window).
  ASSERT_EQ(s.jog_start(JogDirection{{0, -1, 0}}, 1000, 0.3, 0.3), "");
  EXPECT_TRUE(s.jogging());
  EXPECT_EQ(s.take_output(), marlin_frame(4, "G91") + "\n");
  s.on_bytes("ok\n", 0.31);
  const std::string move = s.take_output();
  EXPECT_NE(move.find("G1Y-"), std::string::npos) << move;
  EXPECT_NE(move.find("F1000"), std::string::npos) << move;
  s.on_bytes("ok\n", 0.32);
  EXPECT_EQ(s.take_output(), marlin_frame(6, "G90") + "\n");
  EXPECT_THROW(s.start_job(program({"G1 X1"}), JobMode::Run, 0.33), std::logic_error);
  // Release: M410 at once (the emergency parser acts on it), then G90.
  s.jog_release();
  EXPECT_EQ(s.take_output(), marlin_frame(7, "M410") + "\n");
  s.on_bytes("ok\n", 0.34);  // G90 of the increment
  s.on_bytes("ok\n", 0.35);  // M410
  EXPECT_EQ(s.take_output(), marlin_frame(8, "G90") + "\n");
  s.on_bytes("ok\n", 0.36);
  EXPECT_FALSE(s.jogging());
  EXPECT_EQ(s.take_output(), "");
  EXPECT_FALSE(s.modal().modal.incremental);
  EXPECT_FALSE(s.realtime(Realtime::FeedHold));  // Marlin has no real-time bytes
}
