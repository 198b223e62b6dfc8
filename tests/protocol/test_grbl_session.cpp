#include <gtest/gtest.h>

#include <cmath>

#include <deque>
#include <random>

#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/protocol/grbl_session.hpp"

using namespace cncstream::protocol;

namespace {

const FirmwareProfile& grbl() {
  static const auto p = load_firmware_profile(CNCSTREAM_SOURCE_DIR "/firmware-profiles/grbl-1.1.toml");
  return p;
}

GrblSessionOptions no_poll() {
  GrblSessionOptions o;
  o.poll_status = false;
  return o;
}

PreparedProgram program(const std::vector<std::string>& lines) {
  return prepare_program(lines, "test.nc", grbl().line_length_limit);
}

// Splits engine output into G-code lines (ignoring single real-time bytes).
struct Wire {
  std::string rt;  // real-time bytes seen
  std::vector<std::string> lines;
  std::string partial;
  void take(const std::string& bytes) {
    for (char c : bytes) {
      const auto u = static_cast<unsigned char>(c);
      if (c == '?' || c == '!' || c == '~' || u == 0x18 || u >= 0x80) rt.push_back(c);
      else if (c == '\n') lines.push_back(std::exchange(partial, {}));
      else partial.push_back(c);
    }
  }
};

std::size_t count(const std::vector<Event>& ev, EventKind k) {
  return static_cast<std::size_t>(std::count_if(ev.begin(), ev.end(), [&](const Event& e) { return e.kind == k; }));
}

}  // namespace

TEST(Counting, PopsExactlyOnePerAnswer) {
  CharacterCountingStream c(128, 1);
  PreparedLine a{1, "G1X1", false}, b{2, "G1X22", false};
  c.send(a);
  c.send(b);
  EXPECT_EQ(c.in_flight_bytes(), 5u + 6u);
  auto x = c.answer();
  EXPECT_EQ(x->source_line, 1);
  EXPECT_EQ(c.in_flight_bytes(), 6u);
  EXPECT_EQ(c.answer()->source_line, 2);
  EXPECT_FALSE(c.answer());
  EXPECT_EQ(c.in_flight_bytes(), 0u);
}

TEST(Counting, RespectsCapacityAndSync) {
  CharacterCountingStream c(20, 1);  // capacity 19
  PreparedLine l{1, std::string(9, 'G'), false};  // cost 10
  ASSERT_TRUE(c.can_send(l));
  c.send(l);
  EXPECT_FALSE(c.can_send(l));  // 20 > 19
  PreparedLine s{2, "$100=1", true};
  EXPECT_FALSE(c.can_send(s));  // sync waits for an empty buffer
  c.answer();
  ASSERT_TRUE(c.can_send(s));
  c.send(s);
  EXPECT_FALSE(c.can_send(PreparedLine{3, "G0", false}));  // nothing follows a sync line
}

TEST(GrblSession, StreamsWithinBufferAndCompletes) {
  GrblSession s(grbl(), no_poll());
  std::vector<std::string> lines;
  for (int i = 0; i < 40; ++i) lines.push_back("G1 X" + std::to_string(i) + ".123 Y4.567 F1000 (cut)");
  s.start_job(program(lines), JobMode::Run, 0);
  Wire w;
  w.take(s.take_output());
  std::size_t bytes = 0;
  for (const auto& l : w.lines) bytes += l.size() + 1;
  EXPECT_LE(bytes, 127u);
  EXPECT_GT(w.lines.size(), 3u);
  EXPECT_EQ(w.lines[0], "G1X0.123Y4.567F1000");
  for (int i = 0; i < 200 && s.progress().lines_answered < 40; ++i) {
    s.on_bytes("ok\n", i);
    w.take(s.take_output());
  }
  // Every line answered, but the planner may still be moving: not complete
  // until the controller reports Idle twice in a row (the engine asks).
  EXPECT_EQ(s.progress().state, JobState::Running);
  s.tick(300);
  w.take(s.take_output());
  EXPECT_EQ(w.rt.back(), '?');
  s.on_bytes("<Run|MPos:1,0,0|FS:1000,0>\n<Idle|MPos:2,0,0|FS:0,0>\n", 300.1);
  EXPECT_EQ(s.progress().state, JobState::Running);
  s.on_bytes("<Idle|MPos:2,0,0|FS:0,0>\n", 300.3);
  EXPECT_EQ(s.progress().outcome, JobOutcome::Completed);
  EXPECT_EQ(w.lines.size(), 40u);
  EXPECT_EQ(s.progress().lines_answered, 40u);
  EXPECT_EQ(count(s.take_events(), EventKind::LineAnswered), 40u);
  EXPECT_DOUBLE_EQ(s.modal().feed_rate, 1000);
}

TEST(GrblSession, PushedMessagesPopNothing) {
  GrblSession s(grbl(), no_poll());
  s.start_job(program({"G1X1F100", "G1X2", "G1X3"}), JobMode::Run, 0);
  s.take_output();
  EXPECT_EQ(s.counter().in_flight_count(), 3u);
  s.on_bytes("<Run|MPos:0,0,0|FS:100,0>\n[MSG:Pgm End]\n[GC:G1 G54 G17 G21 G90 G94 M5 M9 T0 F100 S0]\n>G54:ok\n", 1);
  s.on_bytes("[G54:0.000,0.000,0.000]\n", 1);
  EXPECT_EQ(s.counter().in_flight_count(), 3u);
  s.on_bytes("ok\n", 2);
  EXPECT_EQ(s.counter().in_flight_count(), 2u);
}

TEST(GrblSession, RandomLinesNeverOverflowTheController) {
  std::mt19937 rng(1234);
  for (int trial = 0; trial < 5; ++trial) {
    std::uniform_int_distribution<int> len(1, 70);
    std::vector<std::string> lines;
    for (int i = 0; i < 500; ++i) {
      std::string t = "G1X";
      t += std::string(static_cast<std::size_t>(len(rng)), '1');
      lines.push_back(t.substr(0, 80));
    }
    GrblSession s(grbl(), no_poll());
    s.start_job(program(lines), JobMode::Run, 0);
    // A fake controller: bytes land in a 128-byte RX buffer (127 usable);
    // it consumes whole lines at random moments and answers each with ok.
    std::string rx;
    std::size_t max_fill = 0, answered = 0;
    double t = 0;
    while (s.progress().state == JobState::Running) {
      rx += s.take_output();
      max_fill = std::max(max_fill, rx.size());
      ASSERT_LE(rx.size(), 127u) << "overflow";
      const int consume = std::uniform_int_distribution<int>(0, 3)(rng);
      std::string answers;
      for (int k = 0; k < consume; ++k) {
        const auto nl = rx.find('\n');
        if (nl == std::string::npos) break;
        rx.erase(0, nl + 1);
        answers += "ok\n";
        ++answered;
      }
      // Status requests (real-time, never buffered) get Idle once drained.
      const auto q = std::count(rx.begin(), rx.end(), '?');
      rx.erase(std::remove(rx.begin(), rx.end(), '?'), rx.end());
      for (long k = 0; k < q; ++k) answers += rx.empty() ? "<Idle|MPos:0,0,0>\n" : "<Run|MPos:0,0,0>\n";
      s.on_bytes(answers, t += 0.01);
      s.tick(t);
      ASSERT_LT(t, 1000);
    }
    EXPECT_EQ(answered, lines.size());
    EXPECT_GT(max_fill, 100u);  // the buffer was actually used
  }
}

TEST(GrblSession, ErrorHoldsAndReports) {
  GrblSession s(grbl(), no_poll());
  s.start_job(program({"G21", "G1 X10", "G1 X20 F500", "G1 X30"}), JobMode::Run, 0);
  Wire w;
  w.take(s.take_output());
  s.on_bytes("ok\nerror:22\n", 1);
  w.take(s.take_output());
  EXPECT_EQ(s.progress().state, JobState::HeldOnError);
  EXPECT_EQ(w.rt, "!");
  const auto ev = s.take_events();
  const auto it = std::find_if(ev.begin(), ev.end(), [](const Event& e) { return e.kind == EventKind::LineError; });
  ASSERT_NE(it, ev.end());
  EXPECT_EQ(it->source_line, 2);
  EXPECT_EQ(it->code, 22);
  EXPECT_EQ(it->line_text, "G1X10");
  EXPECT_NE(it->text.find("Undefined feed rate"), std::string::npos) << it->text;
  EXPECT_NE(it->text.find("F word"), std::string::npos) << it->text;  // the advice
  // Remaining in-flight lines still get answered; nothing new is sent while held.
  s.on_bytes("ok\nok\n", 2);
  EXPECT_EQ(s.progress().state, JobState::HeldOnError);
  s.resume();
  w.take(s.take_output());
  EXPECT_EQ(w.rt, "!~");
  s.on_bytes("<Idle|MPos:0,0,0>\n<Idle|MPos:0,0,0>\n", 3);
  EXPECT_EQ(s.progress().outcome, JobOutcome::Completed);
}

TEST(GrblSession, StopHoldsWaitsForHold0ThenResetsWithoutAlarm) {
  GrblSession s(grbl(), no_poll());
  std::vector<std::string> lines(50, "G1X1Y1F100");
  s.start_job(program(lines), JobMode::Run, 0);
  s.take_output();
  s.on_bytes("ok\nok\n", 0.5);
  s.take_output();
  s.stop();
  Wire w;
  w.take(s.take_output());
  EXPECT_EQ(w.rt, "!?");
  s.on_bytes("<Hold:1|MPos:1,1,0>\n", 1);  // still decelerating: no reset yet
  w.take(s.take_output());
  EXPECT_EQ(w.rt.find('\x18'), std::string::npos);
  EXPECT_TRUE(w.lines.empty());  // nothing fed while stopping
  s.on_bytes("<Hold:0|MPos:1.2,1.2,0>\n", 1.2);
  w.take(s.take_output());
  EXPECT_NE(w.rt.find('\x18'), std::string::npos);
  // One more ok before the banner answers line 3 (it was parsed before the reset).
  s.on_bytes("ok\r\nGrbl 1.1h ['$' for help]\r\n", 1.3);
  EXPECT_EQ(s.progress().outcome, JobOutcome::Stopped);
  EXPECT_EQ(s.progress().last_answered_line, 3);
  s.on_bytes("ok\n", 1.4);  // a stale ok after the reset pops nothing
  EXPECT_EQ(s.counter().in_flight_count(), 0u);
  EXPECT_EQ(s.counter().in_flight_count(), 0u);
}

TEST(GrblSession, StopWithoutHoldSubstateWaitsForTheMachineToSettle) {
  GrblSession s(grbl(), no_poll());
  s.start_job(program({"G1X100F100", "G1X0"}), JobMode::Run, 0);
  s.take_output();
  s.stop();
  s.take_output();
  s.on_bytes("<Hold|MPos:5,0,0>\n<Hold|MPos:5.5,0,0>\n<Door:2|MPos:5.6,0,0>\n", 1);
  EXPECT_EQ(s.take_output().find('\x18'), std::string::npos);  // still moving
  s.on_bytes("<Hold|MPos:5.6,0,0>\n", 1.2);
  EXPECT_NE(s.take_output().find('\x18'), std::string::npos);
}

TEST(GrblSession, AlarmStopsExplainsAndResetsWhenRequired) {
  GrblSession s(grbl(), no_poll());
  s.start_job(program({"G0X1000", "G1X1F10"}), JobMode::Run, 0);
  s.take_output();
  s.on_bytes("ok\nALARM:2\n[MSG:Reset to continue]\n", 1);
  Wire w;
  w.take(s.take_output());
  EXPECT_EQ(s.progress().outcome, JobOutcome::Alarm);
  EXPECT_NE(w.rt.find('\x18'), std::string::npos);  // soft limit needs a reset
  const auto ev = s.take_events();
  const auto it = std::find_if(ev.begin(), ev.end(), [](const Event& e) { return e.kind == EventKind::Alarm; });
  ASSERT_NE(it, ev.end());
  EXPECT_NE(it->text.find("$X"), std::string::npos) << it->text;
  EXPECT_EQ(it->source_line, 1);
  s.on_bytes("Grbl 1.1h ['$' for help]\n[MSG:'$H'|'$X' to unlock]\n", 2);
  EXPECT_FALSE(s.waiting_for_reset());
  // A probe alarm needs no reset.
  GrblSession p(grbl(), no_poll());
  p.start_job(program({"G38.2Z-10F50"}), JobMode::Run, 0);
  p.take_output();
  p.on_bytes("ALARM:5\n", 1);
  EXPECT_EQ(p.take_output().find('\x18'), std::string::npos);
  EXPECT_EQ(p.progress().outcome, JobOutcome::Alarm);
}

TEST(GrblSession, PauseResumeAndOverrides) {
  GrblSession s(grbl(), no_poll());
  s.start_job(program({"G1X1F100", "G1X2"}), JobMode::Run, 0);
  s.take_output();
  s.pause();
  EXPECT_EQ(s.progress().state, JobState::Paused);
  s.resume();
  EXPECT_TRUE(s.realtime(Realtime::FeedOvPlus10));
  EXPECT_TRUE(s.realtime(Realtime::FeedOvMinus1));
  EXPECT_TRUE(s.realtime(Realtime::RapidOvLow));
  EXPECT_TRUE(s.realtime(Realtime::SpindleOvReset));
  EXPECT_EQ(s.take_output(), "!~\x91\x94\x97\x99");
  EXPECT_FALSE(s.realtime(Realtime::ToolChangeAck));  // not a GRBL 1.1 byte
  GrblSession c(conservative_grbl_subset(grbl()), no_poll());
  EXPECT_FALSE(c.realtime(Realtime::FeedOvPlus10));  // unknown firmware: no extended bytes
  EXPECT_TRUE(c.realtime(Realtime::FeedHold));
}

TEST(GrblSession, PersistentWritesGoOneAtATime) {
  GrblSession s(grbl(), no_poll());
  s.start_job(program({"G21", "G10 L20 P1 X0 Y0", "G1X1F100", "$100=250", "G0X0"}), JobMode::Run, 0);
  Wire w;
  w.take(s.take_output());
  EXPECT_EQ(w.lines, (std::vector<std::string>{"G21"}));  // G10 L20 waits for the buffer to empty
  s.on_bytes("ok\n", 1);
  w.take(s.take_output());
  EXPECT_EQ(w.lines.back(), "G10L20P1X0Y0");
  EXPECT_EQ(w.lines.size(), 2u);  // and nothing follows it
  s.on_bytes("ok\n", 2);
  w.take(s.take_output());
  EXPECT_EQ(w.lines.size(), 3u);  // G1; $100 waits again
  s.on_bytes("ok\n", 3);
  w.take(s.take_output());
  EXPECT_EQ(w.lines.back(), "$100=250");
  EXPECT_EQ(w.lines.size(), 4u);
}

TEST(GrblSession, CheckModeCollectsEveryError) {
  GrblSession s(grbl(), no_poll());
  s.start_job(program({"G21", "G1 X1", "G2 X1 Y1 R0", "G0 X0"}), JobMode::Check, 0);
  Wire w;
  w.take(s.take_output());
  EXPECT_EQ(w.lines, (std::vector<std::string>{"$C"}));
  s.on_bytes("[MSG:Enabled]\nok\n", 1);
  w.take(s.take_output());
  EXPECT_EQ(w.lines.size(), 5u);
  s.on_bytes("ok\nerror:22\nerror:33\nok\n", 2);
  w.take(s.take_output());
  EXPECT_EQ(w.lines.back(), "$C");  // leave check mode
  s.on_bytes("[MSG:Disabled]\nok\nGrbl 1.1h ['$' for help]\n", 3);
  EXPECT_EQ(s.progress().outcome, JobOutcome::CheckFailed);
  ASSERT_EQ(s.progress().check_errors.size(), 2u);
  EXPECT_EQ(s.progress().check_errors[0].source_line, 2);
  EXPECT_EQ(s.progress().check_errors[1].source_line, 3);
  EXPECT_EQ(s.progress().check_errors[1].code, 33);
}

TEST(GrblSession, CheckThenRunStreamsOnlyAfterACleanPass) {
  GrblSession s(grbl(), no_poll());
  s.start_job(program({"G21", "G1 X1 F100"}), JobMode::CheckThenRun, 0);
  Wire w;
  w.take(s.take_output());
  EXPECT_EQ(s.progress().mode, JobMode::Check);
  s.on_bytes("[MSG:Enabled]\nok\n", 1);
  w.take(s.take_output());
  s.on_bytes("ok\nok\n", 1.5);
  w.take(s.take_output());
  EXPECT_EQ(w.lines.back(), "$C");
  s.on_bytes("[MSG:Disabled]\nok\nGrbl 1.1h ['$' for help]\n", 2);
  w.take(s.take_output());
  EXPECT_EQ(s.progress().mode, JobMode::Run);
  EXPECT_EQ(s.progress().state, JobState::Running);
  EXPECT_EQ(w.lines, (std::vector<std::string>{"$C", "G21", "G1X1F100", "$C", "G21", "G1X1F100"}));
  s.on_bytes("ok\nok\n<Idle|MPos:1,0,0>\n<Idle|MPos:1,0,0>\n", 3);
  EXPECT_EQ(s.progress().outcome, JobOutcome::Completed);
  // An error in the pass: nothing is streamed.
  GrblSession f(grbl(), no_poll());
  f.start_job(program({"G1 X1"}), JobMode::CheckThenRun, 0);
  f.take_output();
  f.on_bytes("ok\n", 1);
  f.take_output();
  f.on_bytes("error:22\n", 1.5);
  EXPECT_EQ(count(f.take_events(), EventKind::CheckError), 1u);
  f.take_output();
  f.on_bytes("ok\nGrbl 1.1h ['$' for help]\n", 2);
  EXPECT_EQ(f.progress().outcome, JobOutcome::CheckFailed);
  EXPECT_TRUE(f.take_output().empty());
}

TEST(GrblSession, HeldJogSendsOneIncrementAtATimeAndCancelsOnRelease) {
  GrblSession s(grbl(), no_poll());
  // GRBL's defaults (500 mm/min, 10 mm/s^2): 600 mm/min on a diagonal is
  // limited to what the axes allow; increments last 25 ms or more.
  ASSERT_EQ(s.jog_start(JogDirection{{1, 1, 0}}, 600, 0.3, 0), "");
  Wire w;
  w.take(s.take_output());
  ASSERT_EQ(w.lines.size(), 1u);
  EXPECT_EQ(w.lines[0].rfind("$J=G91G21X", 0), 0u) << w.lines[0];
  EXPECT_NE(w.lines[0].find("F600"), std::string::npos) << w.lines[0];
  s.on_bytes("ok\n", 0.01);
  w.take(s.take_output());
  EXPECT_EQ(w.lines.size(), 2u);
  s.jog_release();
  w.take(s.take_output());
  EXPECT_EQ(w.rt, "\x85");
  // The increment in flight at the release was parsed after it: cancel again.
  s.on_bytes("ok\n", 0.02);
  w.take(s.take_output());
  EXPECT_EQ(w.rt, "\x85\x85");
  EXPECT_EQ(w.lines.size(), 2u);
  EXPECT_NE(s.jog_start(JogDirection{{0, 0, 0}}, 100, 0.3, 0.03), "");
}

TEST(GrblSession, SilentHolderIsCancelledByTheDeadline) {
  GrblSession s(grbl(), no_poll());
  ASSERT_EQ(s.jog_start(JogDirection{{1, 0, 0}}, 300, 0.2, 0), "");
  Wire w;
  w.take(s.take_output());
  s.on_bytes("ok\n", 0.01);
  w.take(s.take_output());
  EXPECT_LE(s.next_deadline(), 0.2 + 1e-9);  // the session's timer wakes for the lease
  s.tick(0.2);
  w.take(s.take_output());
  EXPECT_EQ(w.rt, "\x85");
  bool told = false;
  for (const auto& e : s.take_events()) told |= e.text.find("dead man") != std::string::npos;
  EXPECT_TRUE(told);
}

TEST(GrblSession, StepJogIsOneLineAndRefusedDuringAJob) {
  GrblSession s(grbl(), no_poll());
  ASSERT_EQ(s.jog_step(JogDirection{{0, 0, 1}}, 5, 300, 0), "");
  Wire w;
  w.take(s.take_output());
  ASSERT_EQ(w.lines.size(), 1u);
  EXPECT_EQ(w.lines[0], "$J=G91G21Z5.000F300");
  s.on_bytes("ok\n", 0.1);
  s.start_job(program({"G1 X1 F100"}), JobMode::Run, 0.2);
  EXPECT_NE(s.jog_step(JogDirection{{1, 0, 0}}, 1, 300, 0.2).find("job is running"), std::string::npos);
}

TEST(GrblSession, NextDeadlineIsTheStatusPollOrTheResetTimeOut) {
  GrblSession s(grbl());
  EXPECT_DOUBLE_EQ(s.next_deadline(), 0);  // first poll at once
  s.tick(1.0);
  EXPECT_NEAR(s.next_deadline(), 1.0 + grbl().status_poll_interval_s, 1e-9);
  GrblSession quiet(grbl(), no_poll());
  EXPECT_TRUE(std::isinf(quiet.next_deadline()));
}

TEST(GrblSession, UnexpectedResetAndDisconnectEndTheJob) {
  GrblSession s(grbl(), no_poll());
  s.start_job(program({"G1X1F100", "G1X2", "G1X3"}), JobMode::Run, 0);
  s.on_bytes("ok\n", 1);
  s.on_bytes("Grbl 1.1h ['$' for help]\n", 2);
  EXPECT_EQ(s.progress().outcome, JobOutcome::Error);
  GrblSession d(grbl(), no_poll());
  d.start_job(program({"G1X1F100", "G1X2", "G1X3"}), JobMode::Run, 0);
  d.on_bytes("ok\nok\n", 1);
  d.disconnected();
  EXPECT_EQ(d.progress().outcome, JobOutcome::Disconnected);
  EXPECT_EQ(d.progress().last_answered_line, 2);
  const auto ev = d.take_events();
  EXPECT_NE(ev.back().text.find("line 2"), std::string::npos) << ev.back().text;
}

TEST(GrblSession, PollsStatusAtProfileInterval) {
  GrblSession s(grbl());
  s.tick(0);
  s.tick(0.1);
  s.tick(0.21);
  EXPECT_EQ(s.take_output(), "??");
  GrblSession h(load_firmware_profile(CNCSTREAM_SOURCE_DIR "/firmware-profiles/grblhal.toml"));
  h.on_bytes("<Idle|MPos:0,0,0|MPG:1>\n", 0);
  h.send_command("G0X1");
  EXPECT_EQ(h.take_output(), "");  // pendant owns the stream
  h.on_bytes("<Idle|MPos:0,0,0|MPG:0>\n", 1);
  EXPECT_EQ(h.take_output(), "G0X1\n");
}

TEST(GrblSession, OneKeyPausesResumesAndStartsAProgramPause) {
  GrblSession s(grbl(), no_poll());
  s.start_job(program({"G1X1F100", "M0", "G1X2"}), JobMode::Run, 0);
  s.take_output();
  s.toggle_pause();
  EXPECT_EQ(s.progress().state, JobState::Paused);
  s.toggle_pause();
  EXPECT_EQ(s.progress().state, JobState::Running);
  EXPECT_EQ(s.take_output(), "!~");
  // M0 holds the machine while the job runs: the key is cycle start, once.
  s.on_bytes("ok\nok\n<Hold:0|MPos:1,0,0>\n", 1);
  s.take_output();
  s.toggle_pause();
  EXPECT_EQ(s.take_output(), "~");
  EXPECT_EQ(s.progress().state, JobState::Running);
  // After an error hold, one press continues.
  GrblSession e(grbl(), no_poll());
  e.start_job(program({"G1X1", "G1X2F100"}), JobMode::Run, 0);
  e.take_output();
  e.on_bytes("error:22\n", 1);
  ASSERT_EQ(e.progress().state, JobState::HeldOnError);
  e.take_output();
  e.toggle_pause();
  EXPECT_EQ(e.progress().state, JobState::Running);
  EXPECT_EQ(e.take_output().substr(0, 1), "~");
}

TEST(GrblSession, LinesRefusedAfterAnAlarmAreNeitherProgressNorErrors) {
  GrblSession s(grbl(), no_poll());
  s.start_job(program({"G1X1F100", "G1X2", "G1X3", "G1X4"}), JobMode::Run, 0);
  s.take_output();
  s.on_bytes("ok\nALARM:1\n", 1);
  ASSERT_EQ(s.progress().outcome, JobOutcome::Alarm);
  s.take_events();
  s.on_bytes("error:9\nerror:9\nerror:9\n", 1.1);
  EXPECT_EQ(s.progress().last_answered_line, 1);
  EXPECT_EQ(s.progress().lines_answered, 1u);
  EXPECT_EQ(count(s.take_events(), EventKind::LineError), 0u);
}

TEST(GrblSession, LeavingCheckModeIsAnExpectedResetAndAFailedStartupLineWarns) {
  GrblSession s(grbl(), no_poll());
  s.start_job(program({"G21"}), JobMode::Check, 0);
  s.take_output();
  s.on_bytes("[MSG:Enabled]\nok\nok\n", 1);
  s.take_output();
  s.take_events();
  s.on_bytes("[MSG:Disabled]\nok\nGrbl 1.1h ['$' for help]\n>G1X1:error:22\n", 2);
  EXPECT_EQ(s.progress().outcome, JobOutcome::CheckPassed);
  bool reset_seen = false, startup_warned = false;
  for (const auto& e : s.take_events()) {
    if (e.kind == EventKind::Reset) {
      reset_seen = true;
      EXPECT_EQ(e.text.find("unexpectedly"), std::string::npos) << e.text;
    }
    if (e.kind == EventKind::Warning && e.text.find("startup line 'G1X1' failed: error:22") != std::string::npos)
      startup_warned = true;
  }
  EXPECT_TRUE(reset_seen);
  EXPECT_TRUE(startup_warned);
}

// A dropped end of line: the controller never completes the line, so no
// answer ever comes while it reports Idle. The job used to wait without a
// word until a --timeout (found by the soak); now the silence is reported
// once, naming the line, and a dwell's own seconds are allowed for.
TEST(GrblSession, AnIdleControllerThatNeverAnswersALineIsReported) {
  auto silent = [](const std::vector<std::string>& lines, double quiet_s) {
    GrblSession s(grbl(), no_poll());
    s.start_job(program(lines), JobMode::Run, 0);
    s.take_output();
    s.on_bytes("ok\n", 0.1);  // line 1 answered; line 2 never is
    s.take_events();
    std::vector<Event> warnings;
    for (double t = 0.2; t < 0.1 + quiet_s; t += 0.2) {
      s.on_bytes("<Idle|MPos:1,0,0|FS:0,0>\n", t);
      for (auto& e : s.take_events())
        if (e.kind == EventKind::Warning) warnings.push_back(e);
    }
    return warnings;
  };
  EXPECT_TRUE(silent({"G1 X1 F500", "G1 X2"}, 9.5).empty()) << "not before 10 s";
  const auto w = silent({"G1 X1 F500", "G1 X2"}, 30);
  ASSERT_EQ(w.size(), 1u) << "once per silence";
  EXPECT_EQ(w[0].source_line, 2);
  EXPECT_NE(w[0].text.find("no answer to line 2 'G1X2'"), std::string::npos) << w[0].text;
  EXPECT_NE(w[0].text.find("resume it from the journal"), std::string::npos) << w[0].text;
  // A 20 s dwell is silent and idle for 20 s by design.
  EXPECT_TRUE(silent({"G1 X1 F500", "G4 P20"}, 29).empty());
  EXPECT_EQ(silent({"G1 X1 F500", "G4 P20"}, 31).size(), 1u);
}

TEST(GrblSession, AMovingControllerIsNeverSilentOnALine) {
  GrblSession s(grbl(), no_poll());
  s.start_job(program({"G1 X100 F10", "G1 X0"}), JobMode::Run, 0);
  s.take_output();
  std::size_t warnings = 0;
  // The planner is full of long moves: no answer for a minute, but the machine runs.
  for (double t = 0.2; t < 60; t += 0.2) {
    s.on_bytes("<Run|MPos:1,0,0|FS:10,0>\n", t);
    warnings += count(s.take_events(), EventKind::Warning);
  }
  EXPECT_EQ(warnings, 0u);
}
