// The simulator as hard as GRBL 1.1 at a tool change: M0 holds and runs no
// jog or probe until cycle start; tools have lengths and the tip cuts and
// probes; G38.x against a touch plate and a fixed sensor, with the trigger
// in [PRB], Pn:P, ALARM 4 and 5, the overshoot past the trigger; $#, G10 L2
// and L20, G43.1 lost on a soft reset.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "cncsim/machine.hpp"
#include "cncsim/removal.hpp"
#include "sim_test_util.hpp"

using namespace cncsim;
using simtest::lines_of;
using simtest::send;

namespace {

// A machine with T1 (30 mm stick-out) in the spindle, T2 7.3 mm longer, a
// 5 mm plate centred on X10 Y10 lying on Z0 (its top at Z5), a sensor at
// X100 Y0 with its top at Z-20; the operator mounts tools.
MachineOptions tool_machine() {
  MachineOptions o;
  o.stick_outs = {{1, 30.0}, {2, 37.3}};
  o.start_tool = 1;
  o.operator_mounts_tools = true;
  o.probe_faces.push_back(parse_touch_plate("10,10,5", 0.0));
  o.probe_faces.push_back(parse_tool_sensor("100,0,-20"));
  o.instant_waits = true;
  return o;
}

std::string line_starting(const std::string& out, const std::string& prefix) {
  for (const auto& l : lines_of(out))
    if (l.rfind(prefix, 0) == 0) return l;
  return "";
}

double prb_z(const std::string& out) {
  const std::string l = line_starting(out, "[PRB:");
  const auto c2 = l.find(',', l.find(',') + 1);
  return std::stod(l.substr(c2 + 1));
}

}  // namespace

TEST(ToolChangeSim, M0HoldsAndRunsNoJogOrProbeUntilCycleStart) {
  Machine m(tool_machine());
  m.take_output();
  send(m, "G0 X10 Y10 Z20");
  m.run_until_idle();
  m.receive("M0\n");
  m.advance(0.5);
  EXPECT_EQ(m.state_name(), "Hold:0");
  m.receive("$J=G91 Z-1 F100\n");
  m.receive("G38.2 Z-30 F100\n");
  m.advance(5);
  // Nothing answered, nothing moved: the firmware sits in the M0's suspend.
  EXPECT_EQ(m.take_output().find("ok"), std::string::npos);
  EXPECT_NEAR(m.machine_position().z, 20, 1e-9);
  EXPECT_EQ(m.state_name(), "Hold:0");
  m.receive("~");
  m.advance(0.05);
  m.run_until_idle();
  const auto out = lines_of(m.take_output());
  // The M0 answered, then the jog ran and the probe, arriving during the jog, got error:9.
  ASSERT_GE(out.size(), 3u);
  EXPECT_EQ(out[0], "ok");
  EXPECT_EQ(out[1], "ok");
  EXPECT_EQ(out[2], "error:9");
  EXPECT_NEAR(m.machine_position().z, 19, 1e-9);
}

TEST(ToolChangeSim, M6IsUnsupportedAndTWordsMountNothing) {
  Machine m(tool_machine());
  m.take_output();
  EXPECT_EQ(send(m, "M6"), "error:20\r\n");
  EXPECT_EQ(send(m, "T2 M6"), "error:20\r\n");
  EXPECT_EQ(send(m, "T2"), "ok\r\n");
  m.run_until_idle();
  EXPECT_EQ(m.mounted_tool(), 1) << "GRBL ignores T: only the operator mounts a tool";
  m.request_mount(2);
  m.advance(0.01);
  EXPECT_EQ(m.mounted_tool(), 2);
  EXPECT_NEAR(m.tip_drop(), 7.3, 1e-12);
}

TEST(ToolChangeSim, ProbeTripsWhenTheTipMeetsThePlate) {
  for (const int tool : {1, 2}) {
    Machine m(tool_machine());
    m.take_output();
    m.request_mount(tool);
    send(m, "G0 X10 Y10 Z20");
    m.run_until_idle();
    EXPECT_EQ(m.status_report().find("Pn:"), std::string::npos);
    const std::string out = send(m, "G38.2 Z-10 F100");
    // The tip touches the plate's top (Z5) with the spindle 7.3 mm higher for T2.
    const double expected = 5 + (tool == 2 ? 7.3 : 0);
    ASSERT_FALSE(line_starting(out, "[PRB:").empty()) << out;
    EXPECT_NEAR(prb_z(out), expected, 0.0005) << out;
    EXPECT_NE(line_starting(out, "[PRB:").find(":1]"), std::string::npos);
    m.run_until_idle();
    // It stopped past the trigger (decelerating at 100 mm/min: 0.139 mm), input active.
    EXPECT_LT(m.machine_position().z, expected - 0.1);
    EXPECT_GT(m.machine_position().z, expected - 0.2);
    EXPECT_NE(m.status_report().find("|Pn:P"), std::string::npos);
    // Probing again from there: the input is already active (ALARM:4).
    const std::string again = send(m, "G38.2 Z-10 F20");
    EXPECT_NE(again.find("ALARM:4"), std::string::npos) << again;
    EXPECT_EQ(m.state(), MachineState::Alarm);
    // $# keeps the trigger (machine coordinates) of the last successful probe.
    EXPECT_EQ(send(m, "$X").find("error"), std::string::npos);
    const std::string hash = send(m, "$#");
    EXPECT_NEAR(prb_z(hash), expected, 0.0005) << hash;
  }
}

TEST(ToolChangeSim, NoContactWithinTheTravelIsAlarm5AndG38p3IsNot) {
  Machine m(tool_machine());
  m.take_output();
  send(m, "G0 X50 Y50 Z20");  // nothing under the tool
  m.run_until_idle();
  const std::string out = send(m, "G38.2 Z5 F300");
  m.run_until_idle();
  EXPECT_NE((out + m.take_output()).find("ALARM:5"), std::string::npos) << out;
  EXPECT_NEAR(m.machine_position().z, 5, 1e-6) << "it ran its whole travel, no further";
  EXPECT_EQ(m.state(), MachineState::Alarm);
  EXPECT_EQ(send(m, "G0 Z20"), "error:9\r\n");
  send(m, "$X");
  const std::string soft = send(m, "G38.3 Z0 F300");
  EXPECT_NE(line_starting(soft, "[PRB:").find(":0]"), std::string::npos) << soft;
  EXPECT_NE(m.state(), MachineState::Alarm);
}

TEST(ToolChangeSim, SensorAndAwayProbes) {
  Machine m(tool_machine());
  m.take_output();
  m.request_mount(2);
  send(m, "G0 X100 Y0 Z0");
  m.run_until_idle();
  const std::string approach = send(m, "G38.3 Z-40 F200");
  EXPECT_NEAR(prb_z(approach), -20 + 7.3, 0.0005) << approach;
  m.run_until_idle();
  // Away from the sensor: the input lets go where the tip rises above its top.
  const std::string away = send(m, "G38.4 Z10 F20");
  EXPECT_NEAR(prb_z(away), -20 + 7.3, 0.0005) << away;
  m.run_until_idle();
  EXPECT_EQ(m.status_report().find("Pn:P"), std::string::npos);
  // G38.4 with the input already inactive: ALARM:4.
  EXPECT_NE(send(m, "G38.4 Z10 F20").find("ALARM:4"), std::string::npos);
}

TEST(ToolChangeSim, OffsetsAreReportedWrittenAndTloIsLostOnReset) {
  Machine m(tool_machine());
  m.take_output();
  send(m, "G0 X1 Y2 Z3");
  m.run_until_idle();
  send(m, "G10 L2 P1 Z-3");
  send(m, "G43.1 Z2.5");
  std::string hash = send(m, "$#");
  EXPECT_EQ(line_starting(hash, "[G54:"), "[G54:0.000,0.000,-3.000]");
  EXPECT_EQ(line_starting(hash, "[TLO:"), "[TLO:2.500]");
  // G10 L20: the current position becomes work Z4 (TLO counted, as GRBL does).
  send(m, "G10 L20 P1 Z4");
  hash = send(m, "$#");
  EXPECT_EQ(line_starting(hash, "[G54:"), "[G54:0.000,0.000,-3.500]");
  EXPECT_NEAR(m.work_position().z, 4, 1e-9);
  m.receive(std::string(1, '\x18'));
  m.advance(0.1);
  hash = send(m, "$#");
  EXPECT_EQ(line_starting(hash, "[TLO:"), "[TLO:0.000]") << "G43.1 does not survive a reset";
  EXPECT_EQ(line_starting(hash, "[G54:"), "[G54:0.000,0.000,-3.500]") << "G54 does";
}

TEST(ToolChangeSim, TheTipCutsSoALongerToolNotCompensatedGouges) {
  MachineOptions o = tool_machine();
  Machine m(o);
  StockBox box{{0, 0, -10}, {20, 20, 0}, 0.5};
  MaterialRemoval removal(box, cncstream::cam::parse_cutter_spec("flat:6"));
  removal.set_tool_table(parse_tool_table("1=flat:6@30,2=flat:6@37.3"));
  removal.attach(m);
  m.take_output();
  send(m, "G0 X5 Y5 Z5");
  send(m, "G1 Z-1 F300");
  m.run_until_idle();
  auto lowest = [&] { return *std::min_element(removal.stock().heights().begin(), removal.stock().heights().end()); };
  EXPECT_NEAR(lowest(), -1, 1e-9);
  send(m, "G0 Z5");
  m.run_until_idle();
  m.request_mount(2);
  send(m, "G0 X15 Y15");
  send(m, "G1 Z-1 F300");
  m.run_until_idle();
  EXPECT_NEAR(lowest(), -8.3, 1e-9) << "the longer tool's tip went 7.3 mm deeper";
}

TEST(ToolChangeSim, ToolTableStickOutsAreAllOrNone) {
  EXPECT_EQ(parse_tool_stick_outs("1=flat:6@30,2=ball:3.175@37.3").at(2), 37.3);
  EXPECT_TRUE(parse_tool_stick_outs("1=flat:6,2=ball:3.175").empty());
  EXPECT_THROW(parse_tool_stick_outs("1=flat:6@30,2=ball:3.175"), std::invalid_argument);
  EXPECT_THROW(parse_tool_stick_outs("1=flat:6@-3"), std::invalid_argument);
  EXPECT_THROW(parse_touch_plate("1,2", 0), std::invalid_argument);
}
