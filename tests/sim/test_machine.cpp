#include <gtest/gtest.h>

#include <cmath>

#include "cncsim/machine.hpp"
#include "sim_test_util.hpp"

using namespace cncsim;
using simtest::lines_of;
using simtest::send;

TEST(Machine, BannerOkAndErrors) {
  Machine m;
  EXPECT_EQ(m.take_output(), "\r\nGrbl 1.1h ['$' for help]\r\n");
  EXPECT_EQ(send(m, "G21 G90"), "ok\r\n");
  EXPECT_EQ(send(m, "G1 X1"), "error:22\r\n");
  EXPECT_EQ(send(m, "M6"), "error:20\r\n");
  EXPECT_EQ(send(m, std::string(80, 'X')), "error:11\r\n");
  EXPECT_EQ(send(m, "(just a comment)"), "ok\r\n");
  EXPECT_EQ(send(m, "$Q"), "error:2\r\n");  // read_float fails first, as on the firmware
  EXPECT_EQ(send(m, "$$$"), "error:3\r\n");
}

TEST(Machine, MovesTakeRealisticTime) {
  Machine m;
  m.take_output();
  m.receive("G1 X50 F3000\n");  // 50 mm/s is above $110 = 500 mm/min: capped at 8.33 mm/s
  m.advance(1.0);
  EXPECT_EQ(m.state(), MachineState::Run);
  const std::string s = m.status_report();
  EXPECT_EQ(s.rfind("<Run|MPos:", 0), 0u) << s;
  while (m.state() == MachineState::Run) m.advance(0.001);
  EXPECT_NEAR(m.machine_position().x, 50, 1e-9);
  // 50 mm at 8.333 mm/s with a = 10: 0.833 s accel (3.47 mm) each end + cruise.
  const double v = 500.0 / 60, a = 10, d = v * v / a;
  EXPECT_NEAR(m.now(), 2 * v / a + (50 - d) / v, 0.002);
}

TEST(Machine, StatusReportCadence) {
  Machine m;
  m.take_output();
  EXPECT_EQ(m.status_report(), "<Idle|MPos:0.000,0.000,0.000|FS:0,0|WCO:0.000,0.000,0.000>");
  EXPECT_EQ(m.status_report(), "<Idle|MPos:0.000,0.000,0.000|FS:0,0|Ov:100,100,100>");
  for (int i = 0; i < 8; ++i) EXPECT_EQ(m.status_report(), "<Idle|MPos:0.000,0.000,0.000|FS:0,0>");
  EXPECT_NE(m.status_report().find("WCO:"), std::string::npos);  // every 10th when idle
  send(m, "$10=2");
  send(m, "G92 X-5");
  const std::string r = m.status_report();
  EXPECT_EQ(r, "<Idle|WPos:-5.000,0.000,0.000|Bf:15,128|FS:0,0|WCO:5.000,0.000,0.000>");
}

TEST(Machine, FeedHoldResumeAndReset) {
  Machine m;
  m.take_output();
  send(m, "G1 X100 F500");
  m.advance(2.0);
  m.receive("!");
  EXPECT_EQ(m.state_name(), "Hold:1");
  m.advance(2.0);
  EXPECT_EQ(m.state_name(), "Hold:0");
  const double x = m.machine_position().x;
  m.advance(5.0);
  EXPECT_EQ(m.machine_position().x, x);
  m.receive("~");
  m.advance(1.0);
  EXPECT_EQ(m.state(), MachineState::Run);
  EXPECT_GT(m.machine_position().x, x);
  m.take_output();
  m.receive("\x18");  // reset while moving
  const auto out = lines_of(m.take_output());
  ASSERT_GE(out.size(), 4u);
  EXPECT_EQ(out[0], "ALARM:3");
  EXPECT_EQ(out[2], "Grbl 1.1h ['$' for help]");
  EXPECT_EQ(out[3], "[MSG:'$H'|'$X' to unlock]");
  EXPECT_EQ(send(m, "G0 X0"), "error:9\r\n");
  EXPECT_EQ(send(m, "$X"), "[MSG:Caution: Unlocked]\r\nok\r\n");
  EXPECT_EQ(send(m, "G0 X0"), "ok\r\n");
}

TEST(Machine, SystemCommands) {
  Machine m;
  m.take_output();
  EXPECT_EQ(send(m, "$I"), "[VER:1.1h.20190830:]\r\n[OPT:VNM,15,128]\r\nok\r\n");
  const auto settings = lines_of(send(m, "$$"));
  EXPECT_EQ(settings.front(), "$0=10");
  EXPECT_NE(std::find(settings.begin(), settings.end(), "$11=0.010"), settings.end());
  EXPECT_NE(std::find(settings.begin(), settings.end(), "$130=200.000"), settings.end());
  EXPECT_EQ(send(m, "$G"), "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\nok\r\n");
  EXPECT_EQ(send(m, "$0=2"), "error:6\r\n");
  EXPECT_EQ(send(m, "$20=1"), "error:10\r\n");
  EXPECT_EQ(send(m, "$1=-1"), "error:4\r\n");
  EXPECT_EQ(send(m, "$N0=G20"), "ok\r\n");
  EXPECT_EQ(send(m, "$N"), "$N0=G20\r\n$N1=\r\nok\r\n");
  const auto params = lines_of(send(m, "$#"));
  EXPECT_EQ(params[0], "[G54:0.000,0.000,0.000]");
  EXPECT_EQ(params[10], "[PRB:0.000,0.000,0.000:0]");
  m.receive("\x18");
  EXPECT_NE(m.take_output().find(">G20:ok"), std::string::npos);  // startup line after reset
}

TEST(Machine, CheckMode) {
  Machine m;
  m.take_output();
  send(m, "G10 L20 P1 X5");
  EXPECT_EQ(send(m, "$C"), "[MSG:Enabled]\r\nok\r\n");
  EXPECT_EQ(m.state_name(), "Check");
  EXPECT_EQ(send(m, "G1 X100 F100"), "ok\r\n");
  EXPECT_EQ(send(m, "G1 X1 Y1 Y2"), "error:25\r\n");
  EXPECT_EQ(m.machine_position().x, 0);  // nothing moved
  send(m, "G92 X1");
  const auto out = lines_of(send(m, "$C"));
  ASSERT_GE(out.size(), 4u);
  EXPECT_EQ(out[0], "[MSG:Disabled]");
  EXPECT_EQ(out[1], "ok");
  EXPECT_EQ(out[3], "Grbl 1.1h ['$' for help]");
  EXPECT_EQ(m.state(), MachineState::Idle);
  EXPECT_EQ(m.parser().g92.x, 0);          // G92 cleared by the reset
  EXPECT_EQ(m.parser().coord_system.x, -5);  // G10 data is kept
}

TEST(Machine, JogRulesAndCancel) {
  Machine m;
  m.take_output();
  EXPECT_EQ(send(m, "$J=X10"), "error:22\r\n");
  EXPECT_EQ(send(m, "$J=G1 X10 F100"), "error:16\r\n");
  EXPECT_EQ(send(m, "$J X10 F100"), "error:3\r\n");
  EXPECT_EQ(send(m, "$J=G91 X50 F300"), "ok\r\n");
  EXPECT_EQ(m.state(), MachineState::Jog);
  EXPECT_EQ(send(m, "G0 X0"), "error:9\r\n");
  m.advance(1.0);
  m.receive("\x85");
  m.advance(2.0);
  EXPECT_EQ(m.state(), MachineState::Idle);
  const double x = m.machine_position().x;
  EXPECT_GT(x, 1);
  EXPECT_LT(x, 50);
  EXPECT_NEAR(m.parser().position.x, x, 1e-9);  // parser synced to where the jog stopped
}

TEST(Machine, SoftLimitsAndHoming) {
  Machine m;
  m.take_output();
  EXPECT_EQ(send(m, "$H"), "error:5\r\n");
  send(m, "$22=1");
  send(m, "$20=1");
  EXPECT_EQ(send(m, "$H", 120), "ok\r\n");
  EXPECT_EQ(m.machine_position(), (cncstream::geometry::Vec3{-1, -1, -1}));
  EXPECT_EQ(send(m, "$J=G91 X50 F100"), "error:15\r\n");
  EXPECT_EQ(send(m, "G0 X-10"), "ok\r\n");
  m.take_output();
  m.receive("G0 X10\n");
  m.advance(1);
  const auto out = lines_of(m.take_output());
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0], "ALARM:2");
  EXPECT_EQ(out[1], "[MSG:Reset to continue]");
  m.receive("G0 X-1\n$X\n");  // nothing is answered until a reset
  m.advance(1);
  EXPECT_EQ(m.take_output(), "");
  m.receive("\x18");
  EXPECT_EQ(lines_of(m.take_output()).back(), "[MSG:'$H'|'$X' to unlock]");
}

TEST(Machine, HomingFailureFault) {
  MachineOptions o;
  o.faults.homing_failure = 9;
  Machine m(o);
  send(m, "$22=1");
  m.take_output();
  const auto out = lines_of(send(m, "$H", 120) + m.take_output());
  ASSERT_GE(out.size(), 4u);
  EXPECT_EQ(out[0], "ALARM:9");
  EXPECT_EQ(out[1], "ok");
  EXPECT_EQ(out.back(), "[MSG:'$H'|'$X' to unlock]");
  EXPECT_EQ(m.state(), MachineState::Alarm);
}

TEST(Machine, RxBufferOverflowDropsBytes) {
  Machine m;
  m.take_output();
  std::string burst;
  for (int i = 0; i < 40; ++i) burst += "G1 X" + std::to_string(i % 2 ? 10 : 0) + " Y" + std::to_string(i) + " F100\n";
  m.receive(burst);  // the planner fills at 15 blocks, then the RX buffer at 127 bytes
  EXPECT_GT(m.rx_bytes_dropped(), 0u);
  EXPECT_EQ(m.rx_used(), 127u);
  MachineOptions strict;
  strict.strict = true;
  Machine s(strict);
  EXPECT_THROW(s.receive(burst), RxOverflowError);
}

TEST(Machine, OverridesDwellAndProgramEnd) {
  Machine m;
  m.take_output();
  send(m, "G1 X100 F400");
  m.receive(std::string(1, '\x91'));
  m.advance(0.1);
  m.status_report();
  std::string r = m.status_report();
  for (int i = 0; i < 30 && r.find("Ov:") == std::string::npos; ++i) r = m.status_report();
  EXPECT_NE(r.find("Ov:110,100,100"), std::string::npos) << r;
  m.run_until_idle();
  m.take_output();
  const double t0 = m.now();
  EXPECT_EQ(send(m, "G4 P2"), "ok\r\n");
  EXPECT_NEAR(m.now() - t0, 2.0, 0.06);
  EXPECT_EQ(send(m, "M30"), "[MSG:Pgm End]\r\nok\r\n");
}

TEST(Machine, JogsAndProbesIgnoreTheFeedOverride) {
  // Acceleration high enough that every move here runs at its nominal speed.
  auto fs_feed = [](const std::string& report) {
    const auto at = report.find("|FS:");
    return at == std::string::npos ? -1.0 : std::stod(report.substr(at + 4));
  };
  MachineOptions o;
  o.probe_surface_z = -50;
  Machine m(o);
  m.take_output();
  send(m, "$120=2000");
  send(m, "$121=2000");
  send(m, "$122=2000");
  for (int k = 0; k < 5; ++k) m.receive(std::string(1, '\x91'));  // feed override 150 %
  m.advance(0.01);
  send(m, "G1 X20 F100");
  m.advance(1);
  EXPECT_NEAR(fs_feed(m.status_report()), 150, 1) << "a feed move follows the override";
  m.run_until_idle();
  send(m, "$J=G91 X10 F100");
  m.advance(1);
  EXPECT_NEAR(fs_feed(m.status_report()), 100, 1) << "a jog runs at its own feed";
  m.run_until_idle();
  m.receive("G38.2 Z-100 F100\n");  // answered only once the probe ends: do not wait for it
  m.advance(1);
  const std::string report = m.status_report();
  EXPECT_NEAR(fs_feed(report), 100, 1) << "a probe runs at its own feed: " << report;
  m.run_until_idle();
  EXPECT_NE(m.take_output().find("[PRB:30.000,0.000,-50.000:1]"), std::string::npos);
}

TEST(Machine, M0PausesUntilCycleStart) {
  Machine m;
  m.take_output();
  m.receive("M0\n");
  m.advance(1);
  EXPECT_EQ(m.state_name(), "Hold:0");
  EXPECT_EQ(m.take_output(), "");
  m.receive("~");
  m.advance(0.1);
  EXPECT_EQ(m.take_output(), "ok\r\n");
  EXPECT_EQ(m.state(), MachineState::Idle);
}

TEST(Machine, FaultFlags) {
  MachineOptions o;
  o.faults.error_at[2] = 33;
  o.faults.alarm_at[4] = 1;
  Machine m(o);
  m.take_output();
  EXPECT_EQ(send(m, "G0 X1"), "ok\r\n");
  EXPECT_EQ(send(m, "G0 X2"), "error:33\r\n");
  EXPECT_EQ(send(m, "G0 X3"), "ok\r\n");
  m.receive("G0 X4\n");
  m.advance(1);
  EXPECT_EQ(m.take_output(), "ALARM:1\r\n[MSG:Reset to continue]\r\n");

  MachineOptions v;
  v.faults.vanish_after = 2;
  v.faults.stall_at[1] = 3.0;
  Machine w(v);
  w.take_output();
  w.receive("G0 X1\n");
  w.advance(2.9);
  EXPECT_EQ(w.take_output(), "");  // stalled
  w.advance(0.2);
  EXPECT_EQ(w.take_output(), "ok\r\n");
  send(w, "G0 X2");
  EXPECT_TRUE(w.vanished());
  w.receive("?");
  EXPECT_EQ(w.take_output(), "");

  MachineOptions d;
  d.faults.drop_every = 2;  // "G0X1\n" arrives as "GX\n"
  Machine x(d);
  x.take_output();
  x.receive("G0X1\n");
  x.advance(0.1);
  EXPECT_EQ(x.take_output(), "error:2\r\n");
  MachineOptions c;
  c.faults.corrupt_every = 2;  // "G0X1\n" arrives as "G1X0\n": a feed move without F
  Machine y(c);
  y.take_output();
  y.receive("G0X1\n");
  y.advance(0.1);
  EXPECT_EQ(y.take_output(), "error:22\r\n");
}
