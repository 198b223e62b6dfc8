// Operator controls against the cncsim program in real time: hold and resume,
// overrides that the controller reports back, and a stop that ends in a
// clean reset (Hold:0 first, so no ALARM:3).
#include <gtest/gtest.h>

#include <fstream>

#include "app_run.hpp"
#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/session/stream_runner.hpp"
#include "sim/pty_process.hpp"

using namespace apptest;
using cncstream::protocol::EventKind;
using cncstream::protocol::JobOutcome;
using cncstream::protocol::MachineState;
using cncstream::protocol::Realtime;

TEST(Controls, HoldResumeOverrideAndStopWithoutAlarm) {
  const auto prog = temp_dir() / "slow.nc";
  {
    std::ofstream f(prog);
    f << "G21 G90 G94\n";
    for (int i = 0; i < 400; ++i) f << "G1 X" << (i % 2 ? 0 : 5) << " Y" << i * 0.05 << " F3000\n";
    f << "M2\n";
  }
  simtest::SimProcess sim({"--speed", "4", "--strict"});
  cncstream::session::RunnerOptions o;
  o.port = sim.slave();
  o.profiles_dir = cncstream::protocol::default_profiles_dir();
  o.identify.banner_timeout_s = 0.5;
  o.max_run_s = 20;
  cncstream::session::StreamRunner* runner = nullptr;
  enum class Step { Start, Holding, Resumed, Overridden, Stopping } step = Step::Start;
  bool saw_hold0 = false, saw_run_after = false, saw_ov110 = false, alarm = false;
  std::size_t answered_at_hold = 0, answered_after_hold = 0;
  cncstream::protocol::Axes pos_at_hold{};
  o.on_event = [&](const cncstream::protocol::Event& e) {
    if (e.kind == EventKind::Alarm) alarm = true;
  };
  o.on_tick = [&](const cncstream::session::MachineSnapshot& s) {
    const auto st = s.status ? s.status->state : MachineState::Unknown;
    switch (step) {
      case Step::Start:
        if (s.progress.lines_answered > 20) {
          runner->request_pause();
          step = Step::Holding;
        }
        break;
      case Step::Holding:
        if (st == MachineState::Hold && s.status->substate == 0) {
          if (!saw_hold0) {
            saw_hold0 = true;
            answered_at_hold = s.progress.lines_answered;
            pos_at_hold = *s.status->mpos;
          } else if (s.now > 0 && (*s.status->mpos)[1] == pos_at_hold[1]) {
            answered_after_hold = s.progress.lines_answered;
            runner->request_resume();
            step = Step::Resumed;
          }
        }
        break;
      case Step::Resumed:
        if (st == MachineState::Run) {
          saw_run_after = true;
          runner->request_realtime(Realtime::FeedOvPlus10);
          step = Step::Overridden;
        }
        break;
      case Step::Overridden:
        if (s.overrides && (*s.overrides)[0] == 110) {
          saw_ov110 = true;
          runner->request_stop();
          step = Step::Stopping;
        }
        break;
      case Step::Stopping: break;
    }
  };
  cncstream::session::StreamRunner r(o);
  runner = &r;
  const auto res = r.run(prog);
  EXPECT_EQ(res.outcome, JobOutcome::Stopped) << res.message;
  EXPECT_TRUE(saw_hold0);
  EXPECT_TRUE(saw_run_after);
  EXPECT_TRUE(saw_ov110);
  EXPECT_FALSE(alarm) << "a stop after Hold:0 resets without ALARM:3";
  EXPECT_LT(res.last_answered_line, 300) << "stopped well before the end";
  // While held the buffer may fill up, but it cannot keep streaming the job.
  EXPECT_LE(answered_after_hold, answered_at_hold + 8);
  EXPECT_EQ(sim.stop(), 0) << sim.stderr_text();
}
