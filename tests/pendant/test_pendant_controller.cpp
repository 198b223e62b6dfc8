// The pendant controller with a fake USB receiver (read by the real reader
// thread) and a scripted GRBL on a pseudo-terminal that records every line
// and real-time byte: the dead man on unplug and sleep, reconnection, the
// key map and the LCD frames.
#include <gtest/gtest.h>

#include <optional>

#include <boost/asio/io_context.hpp>

#include <algorithm>
#include <chrono>
#include <functional>
#include <memory>
#include <thread>

#include "cncstream/pendant/pendant_controller.hpp"
#include "cncstream/pendant/usb_pendant_reader.hpp"
#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/session/machine_session.hpp"
#include "cncstream/session/simulator_port.hpp"
#include "fake_pendant_usb.hpp"
#include "session/fake_grbl.hpp"

using namespace cncstream::pendant;
using namespace cncstream::session;
using Clock = std::chrono::steady_clock;

namespace {

// Runs the loop until `done` holds; false after `timeout_s` (generous: the
// condition, not the time, is the test).
bool run_until(boost::asio::io_context& io, const std::function<bool()>& done, double timeout_s = 20) {
  const auto end = Clock::now() + std::chrono::duration<double>(timeout_s);
  while (!done()) {
    if (Clock::now() > end) return false;
    io.run_for(std::chrono::milliseconds(1));
    if (io.stopped()) io.restart();
  }
  return true;
}

// The fake GRBL "powers on" (sends its banner) when the session opens the port.
class FakeGrblPort final : public MachinePort {
 public:
  explicit FakeGrblPort(FakeGrbl& g) : grbl_(g) {}
  std::string path() override { return grbl_.slave_path(); }
  void opened() override { grbl_.reset(); }

 private:
  FakeGrbl& grbl_;
};

std::size_t count_of(const std::string& s, unsigned char c) {
  return static_cast<std::size_t>(std::count(s.begin(), s.end(), static_cast<char>(c)));
}

// Knob at `knob`, axis at `axis`, keys and wheel as given.
InputReport report(std::uint8_t knob, std::uint8_t axis, std::int8_t wheel = 0, std::uint8_t key1 = 0,
                   std::uint8_t key2 = 0) {
  return {0x04, 0x5a, key1, key2, knob, axis, static_cast<std::uint8_t>(wheel), 0x5a};
}

struct Rig {
  FakeGrbl grbl;
  boost::asio::io_context io;
  std::unique_ptr<MachineSession> session;
  FakePendantUsb usb;
  std::unique_ptr<PendantController> controller;
  std::unique_ptr<UsbPendantReader> reader;
  std::vector<std::string> log;

  explicit Rig(PendantConfig cfg) {
    grbl.start();
    MachineOptions o;
    o.name = "fake";
    o.port = std::make_shared<FakeGrblPort>(grbl);
    o.profiles_dir = cncstream::protocol::default_profiles_dir();
    session = std::make_unique<MachineSession>(io, o);
    session->open();
    controller = std::make_unique<PendantController>(*session, std::move(cfg));
    controller->set_log([this](LogLevel, const std::string& t) { log.push_back(t); });
    ReaderOptions ro;
    ro.reopen_delay = std::chrono::milliseconds(100);
    reader = std::make_unique<UsbPendantReader>(usb, *controller, ro);
  }
  ~Rig() {
    reader.reset();
    controller.reset();
    session.reset();
    io.run_for(std::chrono::milliseconds(20));
    grbl.stop();
  }
  bool ready() {
    return run_until(io, [&] { return session->ready() && session->status().has_value(); });
  }
  bool line_seen(const std::string& line) {
    return run_until(io, [&] {
      const auto r = grbl.received();
      return std::find(r.begin(), r.end(), line) != r.end();
    }, 5);
  }
  bool realtime_seen(unsigned char c, std::size_t count = 1) {
    return run_until(io, [&] { return count_of(grbl.realtime_seen(), c) >= count; }, 5);
  }
  bool jog_line_seen(std::size_t after) {
    return run_until(io, [&] {
      const auto r = grbl.received();
      return std::count_if(r.begin(), r.end(), [](const std::string& l) { return l.rfind("$J=", 0) == 0; }) >
             static_cast<std::ptrdiff_t>(after);
    }, 5);
  }
  std::size_t jog_lines() {
    const auto r = grbl.received();
    return static_cast<std::size_t>(
        std::count_if(r.begin(), r.end(), [](const std::string& l) { return l.rfind("$J=", 0) == 0; }));
  }
};

PendantConfig config(double lease_s) {
  PendantConfig c;
  c.lease_s = lease_s;
  c.macros = default_macros();
  return c;
}

}  // namespace

TEST(PendantController, UnpluggedDuringAContinuousJogCancelsWithin100msAndReconnects) {
  // A long lease: only the unplug can stop this jog within 100 ms.
  Rig rig(config(2.0));
  ASSERT_TRUE(rig.ready());
  rig.usb.plug();
  ASSERT_TRUE(run_until(rig.io, [&] { return rig.controller->plugged(); }));
  rig.usb.send(report(0x1b, 0x11));                    // 100 %, X
  rig.usb.send(report(0x1b, 0x11, 0, 0x0e));           // MPG: continuous
  rig.usb.send(report(0x1b, 0x11));
  ASSERT_TRUE(run_until(rig.io, [&] { return rig.controller->mode() == JogMode::Continuous; }));
  rig.usb.send(report(0x1b, 0x11, 4));                 // the wheel: +X at full speed
  ASSERT_TRUE(rig.jog_line_seen(0));
  EXPECT_NE(rig.grbl.received().back().find("X"), std::string::npos) << rig.grbl.received().back();
  // Held and silent for 150 ms: nothing cancels it (the lease is 2 s).
  const auto cancels_before = count_of(rig.grbl.realtime_seen(), 0x85);
  rig.io.run_for(std::chrono::milliseconds(150));
  EXPECT_EQ(count_of(rig.grbl.realtime_seen(), 0x85), cancels_before);
  EXPECT_TRUE(rig.session->snapshot().jogging);

  // Timed from the moment the controller learns of the unplug (on the
  // session's thread): the reader thread's wake-up before it is the
  // operating system's, and on a loaded 2-core machine it alone can exceed
  // 100 ms; what follows is ours (and one pty hop to the fake controller).
  std::optional<Clock::time_point> unplug_seen;
  rig.controller->set_input_tap([&](PendantController::Input in, const InputReport&) {
    if (in == PendantController::Input::Unplug && !unplug_seen) unplug_seen = Clock::now();
  });
  rig.usb.unplug();
  ASSERT_TRUE(run_until(rig.io, [&] { return count_of(rig.grbl.realtime_seen(), 0x85) > cancels_before; }, 2));
  ASSERT_TRUE(unplug_seen);
  const double ms = std::chrono::duration<double, std::milli>(Clock::now() - *unplug_seen).count();
  EXPECT_LE(ms, 100) << "the jog cancel reached the controller " << ms << " ms after the controller saw the unplug";
  rig.controller->set_input_tap({});
  ASSERT_TRUE(run_until(rig.io, [&] { return !rig.controller->plugged(); }));

  // The receiver comes back (a dongle drop-out): it is opened again and the wheel works.
  rig.usb.plug();
  ASSERT_TRUE(run_until(rig.io, [&] { return rig.controller->plugged(); }));
  EXPECT_EQ(rig.usb.opens(), 2);
  ASSERT_TRUE(run_until(rig.io, [&] { return !rig.session->snapshot().jogging; }));
  const auto jogs = rig.jog_lines();
  rig.usb.send(report(0x0f, 0x12));      // after a reconnect the mode is step again: 0.1 mm, Y
  rig.usb.send(report(0x0f, 0x12, -1));
  ASSERT_TRUE(rig.jog_line_seen(jogs));
  EXPECT_NE(rig.grbl.received().back().find("Y-0.1"), std::string::npos) << rig.grbl.received().back();
}

TEST(PendantController, ASleepingPendantCancelsItsJog) {
  Rig rig(config(2.0));
  ASSERT_TRUE(rig.ready());
  rig.usb.plug();
  rig.usb.send(report(0x10, 0x13));
  rig.usb.send(report(0x10, 0x13, 0, 0x0e));
  rig.usb.send(report(0x10, 0x13));
  ASSERT_TRUE(run_until(rig.io, [&] { return rig.controller->mode() == JogMode::Continuous; }));
  rig.usb.send(report(0x10, 0x13, -2));  // -Z, 30 % at half speed
  ASSERT_TRUE(rig.jog_line_seen(0));
  const auto cancels_before = count_of(rig.grbl.realtime_seen(), 0x85);
  const auto asleep_at = Clock::now();
  rig.usb.send({0x04, 0x6a, 0x00, 0x00, 0x00, 0x00, 0x00, 0x6a});
  rig.usb.send({0x04, 0xff, 0xff, 0xff, 0xff, 0xff, 0x81, 0xff});
  ASSERT_TRUE(rig.realtime_seen(0x85, cancels_before + 1));
  const double ms = std::chrono::duration<double, std::milli>(Clock::now() - asleep_at).count();
  EXPECT_LE(ms, 100);
  EXPECT_TRUE(rig.controller->sleeping());
  // Awake again: the plug never went away.
  rig.usb.send(report(0x10, 0x13));
  ASSERT_TRUE(run_until(rig.io, [&] { return !rig.controller->sleeping(); }));
  EXPECT_EQ(rig.usb.opens(), 1);
}

TEST(PendantController, KeysAndMacrosBecomeSessionCommands) {
  Rig rig(config(0.2));
  ASSERT_TRUE(rig.ready());
  rig.usb.plug();
  auto press = [&](std::uint8_t key1, std::uint8_t key2 = 0) {
    rig.usb.send(report(0x0f, 0x12, 0, key1, key2));
    rig.usb.send(report(0x0f, 0x12));
  };
  press(0x08);  // M-Home
  EXPECT_TRUE(rig.line_seen("$H"));
  press(0x09);  // Safe-Z (the fake stands at work Z 3: up to 5)
  EXPECT_TRUE(rig.line_seen("G21G90G0Z5.000"));
  press(0x0b);  // spindle on, then off
  EXPECT_TRUE(rig.line_seen("M3S10000"));
  press(0x0b);
  EXPECT_TRUE(rig.line_seen("M5"));
  press(0x10);  // Macro-10: zero the selected axis (Y)
  EXPECT_TRUE(rig.line_seen("G10L20P0Y0"));
  press(0x0c, 0x0a);  // Fn + W-Home: macro 7, zero all
  EXPECT_TRUE(rig.line_seen("G10L20P0X0Y0Z0"));
  press(0x0c, 0x01);  // Fn + Reset: macro 11, unlock
  EXPECT_TRUE(rig.line_seen("$X"));
  press(0x04);  // Feed+
  EXPECT_TRUE(rig.realtime_seen(0x91));
  press(0x05);  // Feed-
  EXPECT_TRUE(rig.realtime_seen(0x92));
  press(0x06);  // Spindle+
  EXPECT_TRUE(rig.realtime_seen(0x9a));
  press(0x07);  // Spindle-
  EXPECT_TRUE(rig.realtime_seen(0x9b));
  press(0x0c, 0x04);  // Fn + Feed+: macro 1, feed override 100 %
  EXPECT_TRUE(rig.realtime_seen(0x90));
  press(0x0c, 0x06);  // Fn + Spindle+: macro 3, spindle override 100 %
  EXPECT_TRUE(rig.realtime_seen(0x99));
  press(0x0a);  // W-Home: safe Z, then X0 Y0, then Z0
  EXPECT_TRUE(rig.line_seen("G21G90G0X0Y0"));
  EXPECT_TRUE(rig.line_seen("G0Z0"));
  // An unassigned macro says so and sends nothing.
  const auto lines = rig.grbl.received().size();
  press(0x0c, 0x09);  // Fn + Safe-Z: macro 6
  ASSERT_TRUE(run_until(rig.io, [&] {
    return std::any_of(rig.log.begin(), rig.log.end(),
                       [](const std::string& l) { return l.find("macro 6 has no action") != std::string::npos; });
  }, 5));
  rig.io.run_for(std::chrono::milliseconds(50));
  for (std::size_t i = lines; i < rig.grbl.received().size(); ++i) EXPECT_EQ(rig.grbl.received()[i].rfind("G", 0), std::string::npos);
  press(0x02);  // Stop, during no job: a real-time feed hold or reset, never refused
  rig.io.run_for(std::chrono::milliseconds(50));
  EXPECT_TRUE(rig.controller->counters().reports >= 30u);
  EXPECT_EQ(rig.controller->counters().bad_reports, 0u);
}

TEST(PendantController, ConfiguredMacroSendsItsLines) {
  auto cfg = config(0.2);
  cfg.macros[5] = parse_macro_option("5= G0 X1 ; G0 Y2 ").second;
  Rig rig(cfg);
  ASSERT_TRUE(rig.ready());
  rig.usb.plug();
  rig.usb.send(report(0x0f, 0x11, 0, 0x0c, 0x08));  // Fn + M-Home
  EXPECT_TRUE(rig.line_seen("G0X1"));
  EXPECT_TRUE(rig.line_seen("G0Y2"));
}

TEST(PendantController, MacroOptionsAreChecked) {
  EXPECT_EQ(parse_macro_option("7=@zero-all"), (std::pair<int, std::string>{7, "@zero-all"}));
  EXPECT_EQ(parse_macro_option("16=G0 Z10;M5"), (std::pair<int, std::string>{16, "G0 Z10;M5"}));
  for (const char* bad : {"17=@unlock", "0=@unlock", "x=@unlock", "7", "7=", "7=@zero-everything"}) {
    try {
      parse_macro_option(bad);
      ADD_FAILURE() << bad << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}

TEST(PendantController, TheLcdShowsTheMachineEvery200ms) {
  Rig rig(config(0.2));
  ASSERT_TRUE(rig.ready());
  rig.usb.plug();
  rig.usb.send(report(0x0f, 0x11));
  ASSERT_TRUE(run_until(rig.io, [&] { return rig.controller->axis() == AxisKnob::X; }));
  const auto start = rig.usb.features().size();
  rig.io.run_for(std::chrono::milliseconds(1100));
  const auto f = rig.usb.features();
  const auto t = rig.usb.feature_times();
  ASSERT_EQ(f.size() % 3, 0u);
  const std::size_t frames = (f.size() - start) / 3;
  EXPECT_GE(frames, 4u);
  EXPECT_LE(frames, 8u);
  // Mean time between frames near the 200 ms cadence.
  const double span = std::chrono::duration<double, std::milli>(t.back() - t[start]).count();
  EXPECT_GT(span / double(frames - 1), 150);
  EXPECT_LT(span / double(frames - 1), 400);
  // The fake reports MPos 1,2,3 and WCO 0: work X1 Y2 Z3, step mode, no overrides reported (100 %).
  const std::size_t last = f.size() - 3;
  EXPECT_EQ(f[last], (FeatureReport{0x06, 0xfe, 0xfd, 0xfe, 0x81, 0x01, 0x00, 0x00}));
  EXPECT_EQ(f[last + 1], (FeatureReport{0x06, 0x00, 0x02, 0x00, 0x00, 0x00, 0x03, 0x00}));
  EXPECT_EQ(f[last + 2], (FeatureReport{0x06, 0x00, 0x00, 0x64, 0x00, 0x64, 0x00, 0x00}));
  // Fn + Step (macro 16): machine coordinates, shown at once.
  rig.usb.send(report(0x0f, 0x11, 0, 0x0c, 0x0f));
  ASSERT_TRUE(run_until(rig.io, [&] {
    const auto g = rig.usb.features();
    return g.size() >= 3 && g[g.size() - 3][4] == 0x01;
  }, 2));
}

namespace {

// A pendant plugged into a session on the built-in simulator.
struct SimPendant {
  boost::asio::io_context io;
  std::shared_ptr<cncstream::session::SimulatorPort> sim;
  std::unique_ptr<MachineSession> session;
  FakePendantUsb usb;
  std::unique_ptr<PendantController> controller;
  std::unique_ptr<UsbPendantReader> reader;

  SimPendant(const cncstream::session::SimulatorOptions& so, double lease_s,
             std::optional<cncstream::protocol::ToolChangeConfig> tool_change = std::nullopt) {
    sim = std::make_shared<cncstream::session::SimulatorPort>(so);
    MachineOptions o;
    o.name = "sim";
    o.port = sim;
    o.profiles_dir = cncstream::protocol::default_profiles_dir();
    o.tool_change = tool_change;
    session = std::make_unique<MachineSession>(io, o);
    session->open();
    EXPECT_TRUE(run_until(io, [&] { return session->ready() && session->status().has_value(); }));
    controller = std::make_unique<PendantController>(*session, config(lease_s));
    ReaderOptions ro;
    ro.reopen_delay = std::chrono::milliseconds(100);
    reader = std::make_unique<UsbPendantReader>(usb, *controller, ro);
    usb.plug();
  }
  ~SimPendant() {
    reader.reset();
    session->close();
    io.run_for(std::chrono::milliseconds(50));
    sim->finish(false);
  }
};

// The tool-length sensor machine of the tool-change tests: T2 7.3 mm longer than T1.
cncstream::session::SimulatorOptions two_tools_and_a_sensor() {
  cncstream::session::SimulatorOptions so;
  so.speed = "max";
  so.stick_outs = {{1, 30.0}, {2, 37.3}};
  so.tool_sensor = "-30,0,-10";
  return so;
}

cncstream::protocol::ToolChangeConfig sensor_change() {
  cncstream::protocol::ToolChangeConfig tc;
  tc.method = cncstream::protocol::ToolChangeMethod::Sensor;
  tc.safe_z = 30;
  tc.probe_x = -30;
  tc.probe_y = 0;
  return tc;
}

}  // namespace

// The same dead man against the simulated machine: the jog really stops. The
// built-in simulator runs in real time (rates 500 mm/min, 10 mm/s^2); the
// lease is 5 s, so only the unplug can stop the jog this soon.
TEST(PendantController, UnpluggedTheSimulatedMachineStopsWithinItsDeceleration) {
  cncstream::session::SimulatorOptions so;
  so.speed = "1";
  SimPendant rig(so, 5.0);
  auto& io = rig.io;
  auto& session = *rig.session;
  auto& usb = rig.usb;
  auto& controller = *rig.controller;
  usb.send(report(0x1b, 0x11, 0, 0x0e));  // MPG, 100 %, X
  usb.send(report(0x1b, 0x11));
  ASSERT_TRUE(run_until(io, [&] { return controller.mode() == JogMode::Continuous; }));
  // The wheel turns for 0.6 s.
  for (int i = 0; i < 6; ++i) {
    usb.send(report(0x1b, 0x11, 4));
    io.run_for(std::chrono::milliseconds(100));
  }
  const auto mx = [&] {
    const auto st = session.status();
    return st && st->mpos ? (*st->mpos)[0] : 0.0;
  };
  ASSERT_GT(mx(), 0.3) << "the jog did not move";
  usb.unplug();
  const auto unplugged_at = Clock::now();
  ASSERT_TRUE(run_until(io, [&] {
    const auto st = session.status();
    return st && st->state == cncstream::protocol::MachineState::Idle && !session.snapshot().jogging;
  }, 10));
  const double s = std::chrono::duration<double>(Clock::now() - unplugged_at).count();
  // Deceleration from at most 500 mm/min at 10 mm/s^2 takes 0.83 s; status
  // polls add a little, and a loaded 2-core machine more (1.61 s seen while
  // two builds ran). What matters is that the unplug stopped it, not the
  // 5 s lease running out: half of that.
  EXPECT_LT(s, 2.5) << "still moving " << s << " s after the unplug";
  // At most: full speed for the whole time the wheel turned, plus the stop
  // and one increment; the 5 s lease alone would have gone far beyond.
  const double v = 500.0 / 60;
  EXPECT_LT(mx(), v * 0.8 + v * v / 20 + 1.0);
  const double stopped_at = mx();
  io.run_for(std::chrono::milliseconds(500));
  EXPECT_DOUBLE_EQ(mx(), stopped_at);  // nothing queued runs on later
}

// At a tool change the pendant is the operator's hands: its wheel jogs at
// the prompt, Start/Pause continues (the tool is mounted), and the job goes
// on with the new tool measured on the sensor.
TEST(PendantController, AtAToolChangeTheWheelJogsAndStartPauseContinues) {
  SimPendant rig(two_tools_and_a_sensor(), 0.2, sensor_change());
  auto& io = rig.io;
  auto& session = *rig.session;
  auto& usb = rig.usb;
  auto& sim = rig.sim;
  JobInput job;
  job.file = "two-tools.nc";
  job.lines = {"G21 G90", "T1", "G0 Z5", "G1 X10 F500", "T2", "M0", "G1 X20 F500", "M2"};
  job.total_lines = static_cast<std::int64_t>(job.lines.size());
  std::optional<cncstream::protocol::JobOutcome> outcome;
  auto sub = session.subscribe([&](const SessionEvent& e) {
    if (e.kind == SessionEventKind::JobEnded) outcome = e.outcome;
  });
  ASSERT_TRUE(session.start_job(job));
  ASSERT_TRUE(run_until(io, [&] { return session.snapshot().tool_prompt.has_value(); }));
  ASSERT_EQ(session.snapshot().tool_prompt->kind, cncstream::protocol::PromptKind::MountTool);
  // One detent down on Z at 1 mm a step: the machine is the operator's at the prompt.
  const auto mz = [&] { return (*session.status()->mpos)[2]; };
  const double z0 = mz();
  usb.send(report(0x10, 0x13));
  usb.send(report(0x10, 0x13, -1));
  ASSERT_TRUE(run_until(io, [&] { return std::abs(mz() - (z0 - 1)) < 1e-3 && !session.snapshot().jogging; }))
      << mz();
  sim->operator_mount(2);  // the operator's hands
  usb.send(report(0x10, 0x13, 0, 0x03));  // Start/Pause: continue
  usb.send(report(0x10, 0x13));
  ASSERT_TRUE(run_until(io, [&] { return outcome.has_value(); }));
  EXPECT_EQ(*outcome, cncstream::protocol::JobOutcome::Completed);
  EXPECT_EQ(session.snapshot().tool_in_spindle, 2);
  ASSERT_TRUE(session.status() && session.status()->wco);
  EXPECT_NEAR((*session.status()->wco)[2], 7.3, 1e-3);
  sub.reset();
}

// Outside a job the same key answers a routine's prompt: a tool change run
// from the page or the API waits for the tool to be mounted; the wheel jogs
// at the prompt, and Start/Pause confirms it.
TEST(PendantController, AtARoutinesPromptStartPauseConfirms) {
  SimPendant rig(two_tools_and_a_sensor(), 0.2);
  auto& io = rig.io;
  auto& session = *rig.session;
  auto& usb = rig.usb;
  auto& sim = rig.sim;
  std::optional<bool> ended;
  auto sub = session.subscribe([&](const SessionEvent& e) {
    if (e.kind == SessionEventKind::Routine && e.routine_succeeded) ended = *e.routine_succeeded;
  });
  const auto start = session.run_tool_routine(sensor_change(), cncstream::protocol::ToolRoutineKind::Change, 2, 0.1);
  ASSERT_TRUE(start.result) << start.result.reason;
  ASSERT_TRUE(run_until(io, [&] {
    const auto* r = session.routine();
    return r && r->pending_prompt() && r->pending_prompt()->kind == cncstream::protocol::PromptKind::MountTool;
  }));
  // The wheel jogs at the prompt: one detent up on Z at 1 mm a step.
  const auto mz = [&] { return (*session.status()->mpos)[2]; };
  const double z0 = mz();
  usb.send(report(0x10, 0x13));
  usb.send(report(0x10, 0x13, 1));
  ASSERT_TRUE(run_until(io, [&] { return std::abs(mz() - (z0 + 1)) < 1e-3 && !session.snapshot().jogging; })) << mz();
  EXPECT_FALSE(ended.has_value());
  sim->operator_mount(2);
  usb.send(report(0x10, 0x13, 0, 0x03));  // Start/Pause: confirm
  usb.send(report(0x10, 0x13));
  ASSERT_TRUE(run_until(io, [&] { return ended.has_value(); }, 60));
  EXPECT_TRUE(*ended);
  EXPECT_EQ(session.snapshot().tool_in_spindle, 2);
  ASSERT_TRUE(session.status() && session.status()->wco);
  EXPECT_NEAR((*session.status()->wco)[2], 7.3, 1e-3);  // T2 is 7.3 mm longer: the work offset moved with it
  sub.reset();
}
