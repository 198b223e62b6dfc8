// The jog engine alone: requests, answers, status and time in; moves,
// cancels and notes out.
#include <gtest/gtest.h>

#include <cmath>

#include "cncstream/protocol/jog_engine.hpp"

using namespace cncstream::protocol;

namespace {

// A router: 5000 mm/min and 500 mm/s^2 on every axis.
JogLimits router() {
  JogLimits l;
  l.max_rate_mm_min = {5000, 5000, 2000};
  l.accel_mm_s2 = {500, 500, 200};
  return l;
}

StatusReport status(MachineState s, double x, double y, double z) {
  StatusReport r;
  r.state = s;
  r.mpos = Axes{x, y, z, 0, 0, 0};
  return r;
}

double len(const JogMove& m) { return std::hypot(m.delta[0], m.delta[1], m.delta[2]); }

}  // namespace

TEST(JogEngine, ContinuousIncrementsComeFromFeedAndAcceleration) {
  JogEngine j;
  j.set_limits(router());
  j.on_status(status(MachineState::Idle, -10, -10, -1), 0);
  ASSERT_EQ(j.start(JogDirection{{1, 0, 0}}, 3000, 0.3, 0), "");
  // v = 50 mm/s, a = 500 mm/s^2: the controller stops within v^2/2a = 2.5 mm;
  // 3.125 mm queued lets it reach full speed; increments last 25 ms (1.25 mm).
  EXPECT_NEAR(j.stop_distance_mm(), 2.5, 1e-9);
  EXPECT_NEAR(j.increment_mm(), 1.25, 1e-9);
  auto m = j.next_move(0);
  ASSERT_TRUE(m);
  EXPECT_NEAR(m->delta[0], 1.25, 1e-9);
  EXPECT_EQ(m->feed_mm_min, 3000);
  // One increment in flight at a time: at most one can follow a cancel.
  EXPECT_FALSE(j.next_move(0));
  int sent = 1;
  double t = 0;
  for (; sent < 40; ++sent) {
    t += 0.002;  // answers come back within a few ms
    j.on_answer(true, {}, t);
    if (!j.next_move(t)) break;
  }
  // Stops topping up with about 5 mm (0.1 s of motion) ahead, not more.
  EXPECT_GE(sent * 1.25, 5.0);
  EXPECT_LE(sent * 1.25, 5.0 + 1.25 + 0.5);
  const double due = j.next_deadline();
  EXPECT_GT(due, t);
  EXPECT_LT(due, t + 0.05);  // the next increment when the queue has run down one
  EXPECT_TRUE(j.next_move(due + 0.001));
}

TEST(JogEngine, ReleaseCancelsAtOnceAndAgainForALateIncrement) {
  JogEngine j;
  j.set_limits(router());
  j.on_status(status(MachineState::Idle, 0, 0, 0), 0);
  ASSERT_EQ(j.start(JogDirection{{0, -1, 0}}, 1000, 0.3, 0), "");
  ASSERT_TRUE(j.next_move(0));
  j.on_answer(true, {}, 0.01);
  ASSERT_TRUE(j.next_move(0.01));  // in flight when released
  j.release();
  EXPECT_TRUE(j.take_cancel());
  EXPECT_FALSE(j.take_cancel());
  EXPECT_FALSE(j.next_move(0.02));  // nothing new while the cancel winds down
  // The increment in flight was parsed after the cancel: it runs, so cancel again.
  j.on_answer(true, {}, 0.02);
  EXPECT_TRUE(j.take_cancel());
  EXPECT_TRUE(j.busy());
  j.on_status(status(MachineState::Idle, 0, -0.3, 0), 0.2);
  EXPECT_FALSE(j.busy());
}

TEST(JogEngine, DeadManCancelsASilentHolder) {
  JogEngine j;
  j.set_limits(router());
  ASSERT_EQ(j.start(JogDirection{{1, 0, 0}}, 1000, 0.25, 0), "");
  ASSERT_TRUE(j.next_move(0));
  EXPECT_LE(j.next_deadline(), 0.25);
  j.tick(0.2);
  EXPECT_TRUE(j.renew(0.2));  // alive: the lease runs to 0.45
  j.tick(0.44);
  EXPECT_TRUE(j.held());
  EXPECT_FALSE(j.take_cancel());
  j.tick(0.45);
  EXPECT_FALSE(j.held());
  EXPECT_TRUE(j.take_cancel());
  const auto notes = j.take_notes();
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("dead man"), std::string::npos) << notes[0];
  EXPECT_FALSE(j.renew(0.5));
}

TEST(JogEngine, AHeldJogThatNeverSentNeedsNoCancel) {
  JogEngine j;
  ASSERT_EQ(j.start(JogDirection{{1, 0, 0}}, 100, 0.1, 0), "");
  j.release();
  EXPECT_FALSE(j.take_cancel());
  EXPECT_FALSE(j.busy());
}

TEST(JogEngine, StepsQueueTwoDeepAndAFastSpinIsDropped) {
  JogEngine j;
  j.set_limits(router());
  j.on_status(status(MachineState::Idle, 0, 0, 0), 0);
  EXPECT_EQ(j.step(JogDirection{{1, 0, 0}}, 1, 600, 0), "");
  EXPECT_EQ(j.step(JogDirection{{1, 0, 0}}, 1, 600, 0), "");
  const auto third = j.step(JogDirection{{1, 0, 0}}, 1, 600, 0);
  EXPECT_NE(third.find("already queued"), std::string::npos) << third;
  ASSERT_TRUE(j.next_move(0));
  ASSERT_TRUE(j.next_move(0));
  EXPECT_FALSE(j.next_move(0));
  j.on_answer(true, {}, 0.01);
  // An Idle report with a step still in flight (the controller has not
  // parsed it yet) frees nothing.
  j.on_status(status(MachineState::Idle, 0, 0, 0), 0.011);
  EXPECT_EQ(j.steps_outstanding(), 2);
  j.on_answer(true, {}, 0.012);
  // Answered and moving: still two.
  j.on_status(status(MachineState::Jog, 1, 0, 0), 0.1);
  EXPECT_NE(j.step(JogDirection{{1, 0, 0}}, 1, 600, 0.1), "");
  j.on_status(status(MachineState::Idle, 2, 0, 0), 0.2);
  EXPECT_EQ(j.steps_outstanding(), 0);
  EXPECT_EQ(j.step(JogDirection{{1, 0, 0}}, 1, 600, 0.2), "");
}

TEST(JogEngine, DiagonalsMoveTheirLengthWithinTheSlowestAxis) {
  JogEngine j;
  j.set_limits(router());
  ASSERT_EQ(j.step(JogDirection{{3, 4, 0}}, 10, 9000, 0), "");
  auto m = j.next_move(0);
  ASSERT_TRUE(m);
  EXPECT_NEAR(m->delta[0], 6, 1e-9);
  EXPECT_NEAR(m->delta[1], 8, 1e-9);
  EXPECT_NEAR(len(*m), 10, 1e-9);
  EXPECT_NEAR(m->feed_mm_min, 5000 / 0.8, 1e-6);  // Y (0.8 of the move) reaches its 5000 mm/min first
}

TEST(JogEngine, SoftLimitsClampToTravelAndSaySo) {
  JogLimits l = router();
  l.travel_mm = std::array<double, 3>{300, 200, 80};
  JogEngine j;
  j.set_limits(l);
  j.on_status(status(MachineState::Idle, -2, -100, -1), 0);
  ASSERT_EQ(j.step(JogDirection{{1, 0, 0}}, 5, 600, 0), "");
  auto m = j.next_move(0);
  ASSERT_TRUE(m);
  EXPECT_NEAR(m->delta[0], 2, 1e-9);  // to X0, the travel's edge
  auto notes = j.take_notes();
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("shortened"), std::string::npos) << notes[0];
  j.on_answer(true, {}, 0.01);
  j.on_status(status(MachineState::Idle, 0, -100, -1), 1);
  // At the edge: a further step is dropped with a note, nothing sent.
  ASSERT_EQ(j.step(JogDirection{{1, 0, 0}}, 5, 600, 1), "");
  EXPECT_FALSE(j.next_move(1));
  EXPECT_EQ(j.take_notes().size(), 1u);
  // A held jog down stops at Z -80.
  ASSERT_EQ(j.start(JogDirection{{0, 0, -1}}, 2000, 0.3, 1), "");
  double z = -1, t = 1;
  while (auto mv = j.next_move(t)) {
    z += mv->delta[2];
    t += 0.01;
    j.on_answer(true, {}, t);
    j.on_status(status(MachineState::Jog, 0, -100, z), t);
    j.renew(t);
  }
  EXPECT_NEAR(z, -80, 1e-9);
  EXPECT_FALSE(j.take_notes().empty());
}

TEST(JogEngine, RefusedInAlarmHoldAndCheckModeAndForgottenOnAlarm) {
  JogEngine j;
  j.on_status(status(MachineState::Alarm, 0, 0, 0), 0);
  EXPECT_NE(j.step(JogDirection{{1, 0, 0}}, 1, 100, 0).find("alarm"), std::string::npos);
  j.on_status(status(MachineState::Hold, 0, 0, 0), 0);
  EXPECT_NE(j.start(JogDirection{{1, 0, 0}}, 100, 0.3, 0).find("Hold"), std::string::npos);
  j.on_status(status(MachineState::Check, 0, 0, 0), 0);
  EXPECT_NE(j.step(JogDirection{{1, 0, 0}}, 1, 100, 0).find("check"), std::string::npos);
  EXPECT_NE(j.step(JogDirection{{0, 0, 0}}, 1, 100, 0), "");
  EXPECT_NE(j.step(JogDirection{{1, 0, 0}}, -1, 100, 0), "");
  j.on_status(status(MachineState::Idle, 0, 0, 0), 0);
  ASSERT_EQ(j.start(JogDirection{{1, 0, 0}}, 100, 0.3, 0), "");
  ASSERT_TRUE(j.next_move(0));
  j.on_status(status(MachineState::Alarm, 0, 0, 0), 0.1);  // e.g. a limit switch
  EXPECT_FALSE(j.busy());
  EXPECT_FALSE(j.take_cancel());  // the controller dropped everything itself
}

TEST(JogEngine, AControllerErrorEndsTheHeldJog) {
  JogEngine j;
  j.on_status(status(MachineState::Idle, 0, 0, 0), 0);
  ASSERT_EQ(j.start(JogDirection{{1, 0, 0}}, 600, 0.3, 0), "");
  ASSERT_TRUE(j.next_move(0));
  j.on_answer(true, {}, 0.01);
  ASSERT_TRUE(j.next_move(0.01));
  j.on_answer(false, "error:15 (travel exceeded)", 0.02);
  EXPECT_FALSE(j.held());
  EXPECT_TRUE(j.take_cancel());  // the first increment is still moving
  const auto notes = j.take_notes();
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("error:15"), std::string::npos);
}
