// A machine session's jogs and machine actions against the in-process
// simulator: the dead man through the session's own timer, work zero,
// probing Z with a touch plate, going back to work zero, refusals.
#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>

#include <chrono>
#include <cmath>
#include <functional>
#include <thread>

#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/session/machine_session.hpp"
#include "support/run_until.hpp"
#include "cncstream/session/simulator_port.hpp"

using namespace cncstream::session;
using cncstream::protocol::EventKind;
using cncstream::protocol::JogDirection;
using cncstream::protocol::MachineState;

namespace {

// Jogs renew every few ms: a finer slice of the loop.
bool run_until(boost::asio::io_context& io, const std::function<bool()>& done, double timeout_s = 60) {
  return cncstream::test::run_until(io, done, timeout_s, std::chrono::milliseconds(5));
}

MachineOptions machine(std::shared_ptr<MachinePort> port) {
  MachineOptions o;
  o.name.assign(1, 'm');  // (a literal here trips GCC 12's false -Wrestrict)
  o.port = std::move(port);
  o.profiles_dir = cncstream::protocol::default_profiles_dir();
  return o;
}

bool idle_at(const MachineSession& s, double x, double y, double z, bool work) {
  const auto st = s.status();
  if (!st || st->state != MachineState::Idle) return false;
  const auto& p = work ? st->wpos : st->mpos;
  return p && std::abs((*p)[0] - x) < 1e-3 && std::abs((*p)[1] - y) < 1e-3 && std::abs((*p)[2] - z) < 1e-3;
}

}  // namespace

TEST(SessionJog, TheSessionsTimerCancelsASilentHolder) {
  boost::asio::io_context io;
  SimulatorOptions so;
  so.speed = "1";  // real time: the lease is a real time
  auto sim = std::make_shared<SimulatorPort>(so);
  MachineSession s(io, machine(sim));
  double cancelled_at = -1;
  auto sub = s.subscribe([&](const SessionEvent& e) {
    if (e.kind == SessionEventKind::Controller && e.controller.text.find("dead man") != std::string::npos)
      cancelled_at = e.at;
  });
  s.open();
  ASSERT_TRUE(run_until(io, [&] { return s.ready() && s.status(); }));
  const double started = s.now();
  ASSERT_TRUE(s.jog_start(JogDirection{{1, 0, 0}}, 300, 0.2));
  ASSERT_TRUE(run_until(io, [&] { return cancelled_at >= 0; }, 10));
  // The bound: cancelled within 100 ms of the holder's silence.
  EXPECT_LE(cancelled_at - started, 0.2 + 0.1);
  EXPECT_GE(cancelled_at - started, 0.2);
  EXPECT_FALSE(s.jog_renew());  // gone: the holder must start again
  ASSERT_TRUE(run_until(io, [&] { return !s.snapshot().jogging && s.status()->state == MachineState::Idle; }, 10));
  // 300 mm/min for 0.2 s is 1 mm, plus what was queued and the stop.
  EXPECT_LT((*s.status()->mpos)[0], 3.0);
}

TEST(SessionJog, ZeroProbeAndReturnToWorkZero) {
  boost::asio::io_context io;
  SimulatorOptions so;
  so.probe_surface_z = -20;  // the plate's top, machine Z
  auto sim = std::make_shared<SimulatorPort>(so);
  MachineOptions o = machine(sim);
  o.actions.probe_plate_mm = 10;
  o.actions.probe_retract_mm = 2;
  o.actions.probe_travel_mm = 30;
  MachineSession s(io, o);
  std::vector<std::string> logs;
  auto sub = s.subscribe([&](const SessionEvent& e) {
    if (e.kind == SessionEventKind::Log) logs.push_back(e.text);
  });
  s.open();
  ASSERT_TRUE(run_until(io, [&] { return s.ready() && s.status(); }));

  ASSERT_TRUE(s.jog_step(JogDirection{{1, 0, 0}}, 5, 1000));
  ASSERT_TRUE(s.jog_step(JogDirection{{0, 1, 0}}, 3, 1000));
  ASSERT_TRUE(run_until(io, [&] { return idle_at(s, 5, 3, 0, false) && !s.snapshot().jogging; }));
  ASSERT_TRUE(s.zero_axes("XY"));
  ASSERT_TRUE(run_until(io, [&] { return idle_at(s, 0, 0, 0, true); }));

  ASSERT_TRUE(s.probe_z());
  EXPECT_FALSE(s.jog_step(JogDirection{{1, 0, 0}}, 1, 100));  // not while probing
  // Touch at machine Z -20: work Z there is the plate's 10 mm; then 2 mm up.
  ASSERT_TRUE(run_until(io, [&] { return idle_at(s, 0, 0, 12, true) && idle_at(s, 5, 3, -18, false); }))
      << "status " << (s.status() && s.status()->wpos ? (*s.status()->wpos)[2] : -999);
  bool told = false;
  for (const auto& l : logs) told |= l.find("touched at machine Z -20.000") != std::string::npos;
  EXPECT_TRUE(told);

  ASSERT_TRUE(s.safe_z());  // already above 5 mm: nothing moves
  ASSERT_TRUE(s.go_to_work_zero());
  ASSERT_TRUE(run_until(io, [&] { return idle_at(s, 0, 0, 0, true) && idle_at(s, 5, 3, -30, false); }));
  EXPECT_TRUE(s.spindle(true));
  EXPECT_TRUE(s.spindle(false));
  EXPECT_FALSE(s.zero_axes("Q"));
}
