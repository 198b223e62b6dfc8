// The GRBL engine's jogs against the simulated firmware in virtual time (no
// threads, no clock): how far the machine runs on after a release, after a
// silent holder, and how step jogs add up. Deterministic, so the bounds are
// exact properties rather than timings.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "cncsim/machine.hpp"
#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/protocol/grbl_session.hpp"
#include "cncstream/protocol/grbl_settings.hpp"
#include "cncstream/protocol/jog_engine.hpp"

using namespace cncstream::protocol;

namespace {

const FirmwareProfile& grbl() {
  static const auto p = load_firmware_profile(default_profiles_dir() / "grbl-1.1.toml");
  return p;
}

// A host engine and a simulated GRBL wired together, stepping 1 ms at a time.
struct Bench {
  cncsim::Machine machine;
  GrblSession host{grbl()};
  double t = 0;
  std::string cancels;  // jog-cancel bytes the host wrote, in order

  explicit Bench(const std::vector<std::string>& settings) {
    step_for(0.05);  // banner
    for (const auto& s : settings) host.send_command(s);
    GrblSettings table;
    for (const auto& s : settings)
      if (auto kv = parse_setting_line(s)) table[kv->first] = kv->second;
    host.set_jog_limits(jog_limits_from(table));
    step_for(0.2);
  }
  void step() {
    const std::string out = host.take_output();
    for (char c : out)
      if (static_cast<unsigned char>(c) == 0x85) cancels.push_back(c);
    machine.receive(out);
    machine.advance(0.001);
    t += 0.001;
    host.on_bytes(machine.take_output(), t);
    if (host.next_deadline() <= t) host.tick(t);
  }
  void step_for(double s) {
    const double end = t + s;
    while (t < end) step();
  }
  double x() const { return machine.machine_position().x; }
};

// 1000 mm/min on X: a router's 2000 mm/min and 50 mm/s^2 (stops in 2.78 mm).
const std::vector<std::string> kRouter = {"$110=2000", "$111=2000", "$112=600", "$120=50", "$121=50", "$122=20"};

}  // namespace

TEST(JogOnSim, ReleaseStopsWithinTheDecelerationPlusOneIncrement) {
  Bench b(kRouter);
  ASSERT_EQ(b.host.jog_start(JogDirection{{1, 0, 0}}, 1000, 0.3, b.t), "");
  const double stop = b.host.jog().stop_distance_mm(), inc = b.host.jog().increment_mm();
  EXPECT_NEAR(stop, (1000.0 / 60) * (1000.0 / 60) / 100, 1e-9);
  for (int i = 0; i < 20; ++i) {  // held for 2 s, renewed every 100 ms
    b.step_for(0.1);
    ASSERT_TRUE(b.host.jog_renew(b.t));
  }
  EXPECT_EQ(b.machine.state(), cncsim::MachineState::Jog);
  const double before = b.x();
  EXPECT_GT(before, 25);  // it did run at speed (2 s at 16.7 mm/s, less the ramp)
  b.host.jog_release();
  const double at_release = b.x();
  b.step_for(3);
  EXPECT_EQ(b.machine.state(), cncsim::MachineState::Idle);
  EXPECT_FALSE(b.host.jogging());
  const double run_on = b.x() - at_release;
  EXPECT_LE(run_on, stop + inc + 1e-6) << "stop " << stop << " increment " << inc;
  EXPECT_GT(run_on, 0.5 * stop);  // it was moving at speed, and decelerated
  // No line left behind in the controller to run later.
  const double settled = b.x();
  b.step_for(1);
  EXPECT_DOUBLE_EQ(b.x(), settled);
}

TEST(JogOnSim, ASilentHolderIsStoppedByTheDeadMan) {
  Bench b(kRouter);
  ASSERT_EQ(b.host.jog_start(JogDirection{{0, 1, 0}}, 1000, 0.25, b.t), "");
  const double started = b.t;
  while (b.cancels.empty() && b.t < started + 2) b.step();
  ASSERT_EQ(b.cancels.size(), 1u);
  EXPECT_LE(b.t - started, 0.25 + 0.002);  // the lease, to the tick
  b.step_for(2);
  EXPECT_EQ(b.machine.state(), cncsim::MachineState::Idle);
  // It never got past the motion queued within the lease plus its stop.
  const double v = 1000.0 / 60;
  EXPECT_LE(b.machine.machine_position().y, v * 0.25 + v * v / 100 + b.host.jog().increment_mm() + 1e-6);
}

TEST(JogOnSim, StepsAddUpExactlyAndAFastSpinIsBounded) {
  Bench b(kRouter);
  for (int i = 0; i < 5; ++i) {
    ASSERT_EQ(b.host.jog_step(JogDirection{{0, 0, -1}}, 0.1, 300, b.t), "");
    b.step_for(0.5);
  }
  EXPECT_NEAR(b.machine.machine_position().z, -0.5, 1e-9);
  // Fifty detents at once: two are taken, the rest refused; the machine stops
  // two steps later, not fifty.
  int accepted = 0;
  for (int i = 0; i < 50; ++i) accepted += b.host.jog_step(JogDirection{{1, 0, 0}}, 1, 1000, b.t).empty();
  EXPECT_EQ(accepted, 2);
  b.step_for(2);
  EXPECT_NEAR(b.x(), 2, 1e-9);
}
