// The tool-change routine (protocol/tool_change.hpp) against the simulated
// GRBL 1.1 with tool lengths, a touch plate and a sensor: what it sends, what
// it sets the work offset to, and that it fails closed.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "cncsim/machine.hpp"
#include "cncstream/protocol/status_report.hpp"
#include "cncstream/protocol/tool_change.hpp"
#include "support/routine_bench.hpp"

using namespace cncstream;
using namespace cncstream::protocol;

namespace {

constexpr double kSafeZ = 40;

// T1 (30 mm stick-out) in the spindle, T2 7.3 mm longer; a 5 mm plate on
// Z0 centred on X10 Y10 (top at Z5), a sensor at X100 Y0 with its top at Z0;
// G54 Z at -2 (the operator zeroed T1 there).
cncsim::MachineOptions bench_machine(double t2_stick_out = 37.3) {
  cncsim::MachineOptions o;
  o.stick_outs = {{1, 30.0}, {2, t2_stick_out}};
  o.start_tool = 1;
  o.operator_mounts_tools = true;
  o.probe_faces.push_back(cncsim::parse_touch_plate("10,10,5", 0.0));
  o.probe_faces.push_back(cncsim::parse_tool_sensor("100,0,0"));
  return o;
}

ToolChangeConfig plate_config() {
  ToolChangeConfig c;
  c.method = ToolChangeMethod::Plate;
  c.safe_z = kSafeZ;
  c.probe_x = 10;
  c.probe_y = 10 + 2;  // work XY: G54 Y is -2 below
  c.probe_travel = 50;
  return c;
}

ToolChangeConfig sensor_config() {
  ToolChangeConfig c = plate_config();
  c.method = ToolChangeMethod::Sensor;
  c.probe_x = 100;
  c.probe_y = 0;
  return c;
}

struct Bench {
  cncsim::Machine m;
  std::vector<std::string> sent;
  std::vector<ToolChangePrompt> prompts;
  std::string alarms;
  double lowest_xy_travel_z = 1e9;  // the spindle's lowest Z on any move with XY motion
  std::function<bool(const ToolChangePrompt&)> operator_action = [this](const ToolChangePrompt& p) {
    if (p.kind == PromptKind::Question) return false;
    m.request_mount(p.tool);
    return true;
  };

  explicit Bench(cncsim::MachineOptions o = bench_machine()) : m(std::move(o)) {
    m.take_output();
    command("G10 L2 P1 Y-2 Z-2");
    command("G0 X20 Y15 Z5");
    command("M3 S10000");
    command("G1 F600");
    m.run_until_idle();
    m.take_output();
    m.set_motion_observer([this](const geometry::Vec3& a, const geometry::Vec3& b, bool) {
      if (std::hypot(b.x - a.x, b.y - a.y) > 1e-9)
        lowest_xy_travel_z = std::min(lowest_xy_travel_z, std::min(a.z, b.z) + m.tip_drop());
    });
  }
  void command(const std::string& l) {
    m.receive(l + "\n");
    m.run_until_idle();
  }
  ToolChangeRequest request(int from = 1, int to = 2) const {
    ToolChangeRequest r;
    r.line = 42;
    r.from_tool = from;
    r.to_tool = to;
    r.note = "T2 ball";
    r.modal = m.parser();
    // The engine's modal state knows no offsets: positions in work coordinates.
    r.modal.position = m.work_position();
    r.modal.coord_system = {};
    r.modal.coords = {};
    return r;
  }
  void run(ToolChangeRoutine& r, double max_s = 600, const std::function<void(double)>& each = {}) {
    r.start();
    for (double t = 0; t < max_s && !r.finished(); t += 0.05) {
      if (auto l = r.take_line()) {
        sent.push_back(*l);
        m.receive(*l + "\n");
      }
      if (auto p = r.take_prompt()) {
        prompts.push_back(*p);
        if (operator_action(*p)) r.confirm();
        else r.decline();
      }
      if (each) each(t);
      m.advance(0.05);
      for (const auto& l : cncstream::test::controller_lines(m.take_output())) {
        if (l == "ok") r.on_answer(true, 0);
        else if (l.rfind("error:", 0) == 0) r.on_answer(false, std::stoi(l.substr(6)));
        else if (l.rfind("ALARM:", 0) == 0) {
          alarms += l;
          r.abort("alarm " + l);  // the engine ends the job; the session aborts the routine
        } else if (l.front() == '[') r.on_message(l);
      }
      if (auto st = parse_status_report(m.status_report())) r.on_status(*st);
    }
  }
  bool sent_any(const std::string& prefix) const {
    for (const auto& l : sent)
      if (l.rfind(prefix, 0) == 0) return true;
    return false;
  }
  double g54_z() const { return m.parser().coords.wcs[0].z; }
};

}  // namespace

TEST(ToolChangeRoutine, PlateMeasuresBothToolsAndMovesTheWorkZByTheDifference) {
  Bench b;
  ToolChangeRoutine r(plate_config(), b.request(), std::nullopt);
  b.run(r);
  ASSERT_TRUE(r.succeeded()) << r.failure();
  // 7.3 mm longer: the work offset's Z goes up by 7.3 (PRB is to 0.001 mm).
  EXPECT_NEAR(b.g54_z(), -2 + 7.3, 0.0015);
  EXPECT_EQ(b.m.mounted_tool(), 2);
  // So the new tip at work Z0 is where the old one was.
  ASSERT_EQ(b.prompts.size(), 1u);
  EXPECT_EQ(b.prompts[0].kind, PromptKind::MountTool);
  // Spindle and coolant off first, then up at G53; fast then slow probes.
  ASSERT_GE(b.sent.size(), 4u);
  EXPECT_EQ(b.sent[0], "M5");
  EXPECT_EQ(b.sent[1], "M9");
  EXPECT_EQ(b.sent[3], "G53 G0 Z40.000");
  EXPECT_TRUE(b.sent_any("G91 G38.2 Z-50.000 F150.000"));
  EXPECT_TRUE(b.sent_any("G38.2 Z-4.000 F20.000"));
  EXPECT_TRUE(b.sent_any("G10 L2 P1 Z5.300") || b.sent_any("G10 L2 P1 Z5.299") || b.sent_any("G10 L2 P1 Z5.301"));
  // No XY travel below the safe Z.
  EXPECT_GE(b.lowest_xy_travel_z, kSafeZ - 1e-9);
  // Back where the program was, spindle on with its speed before Z comes down, modal G1 F600 again.
  const auto m3 = std::find(b.sent.begin(), b.sent.end(), "M3 S10000");
  const auto z = std::find(b.sent.begin(), b.sent.end(), "G0 Z5.000");
  ASSERT_NE(m3, b.sent.end());
  ASSERT_NE(z, b.sent.end());
  EXPECT_LT(m3, z);
  EXPECT_EQ(*(m3 + 1), "G4 P4.0");
  EXPECT_EQ(b.sent.back(), "G1 F600.000");
  b.m.run_until_idle();  // the routine ends with its last answer; the return's moves run on
  EXPECT_NEAR(b.m.work_position().x, 20, 1e-9);
  EXPECT_NEAR(b.m.work_position().y, 15, 1e-9);
  EXPECT_NEAR(b.m.work_position().z, 5, 1e-9);
  EXPECT_EQ(b.m.parser().modal.motion, gcode::MotionMode::Linear);
  EXPECT_EQ(b.m.parser().modal.spindle, gcode::SpindleState::CW);
  const auto rec = r.record();
  EXPECT_TRUE(rec.length_known);
  EXPECT_EQ(rec.tool, 2);
  ASSERT_TRUE(rec.offset_z);
  ASSERT_TRUE(r.reference());
  EXPECT_EQ(r.reference()->tool, 1);
  EXPECT_NEAR(r.reference()->offset_z, -2, 1e-9);
}

TEST(ToolChangeRoutine, SensorApproachesWithG38p3AndTheReferenceIsKeptForTheNextChange) {
  Bench b;
  ToolChangeRoutine first(sensor_config(), b.request(1, 2), std::nullopt);
  b.run(first);
  ASSERT_TRUE(first.succeeded()) << first.failure();
  EXPECT_TRUE(b.sent_any("G53 G0 X100.000 Y0.000"));
  EXPECT_TRUE(b.sent_any("G91 G38.3 Z-50.000"));
  EXPECT_NEAR(b.g54_z(), -2 + 7.3, 0.0015);
  // Back to T1: only the new tool is measured (one fast probe), the offset returns to T1's.
  b.sent.clear();
  ToolChangeRoutine second(sensor_config(), b.request(2, 1), first.reference());
  b.run(second);
  ASSERT_TRUE(second.succeeded()) << second.failure();
  EXPECT_EQ(std::count_if(b.sent.begin(), b.sent.end(), [](const std::string& l) { return l.find("G38.3") != std::string::npos; }), 1);
  EXPECT_NEAR(b.g54_z(), -2, 0.0015);
}

TEST(ToolChangeRoutine, SameToolIsSkippedWithoutMotion) {
  Bench b;
  ToolChangeRoutine r(plate_config(), b.request(2, 2), std::nullopt);
  b.run(r);
  EXPECT_TRUE(r.succeeded());
  EXPECT_TRUE(b.sent.empty());
  EXPECT_TRUE(r.record().skipped);
}

TEST(ToolChangeRoutine, ProbeInputActiveBeforeProbingIsRefused) {
  // A clip shorted to the plate: the input is active everywhere.
  cncsim::MachineOptions o = bench_machine();
  o.probe_surface_z = 1000;
  Bench b(o);
  ToolChangeRoutine r(plate_config(), b.request(), std::nullopt);
  b.run(r);
  EXPECT_FALSE(r.succeeded());
  EXPECT_NE(r.failure().find("probe input is active"), std::string::npos) << r.failure();
  EXPECT_FALSE(b.sent_any("G91 G38"));
  EXPECT_TRUE(b.alarms.empty());
  EXPECT_NEAR(b.g54_z(), -2, 1e-12);
}

TEST(ToolChangeRoutine, NoPlateAlarm5StopsWithinTheTravelAndTheLengthIsUnknown) {
  Bench b;
  ToolChangeConfig c = plate_config();
  c.probe_x = 60;  // nothing there
  // A reference from before: the new tool is measured at once, after it was mounted.
  const ToolLengthReference ref{1, 7.0, -2, ToolChangeMethod::Plate};
  ToolChangeRoutine r(c, b.request(), ref);
  b.run(r);
  EXPECT_FALSE(r.succeeded());
  EXPECT_NE(b.alarms.find("ALARM:5"), std::string::npos);
  // The probe ran its 50 mm and no further.
  EXPECT_NEAR(b.m.machine_position().z, kSafeZ - 50, 1e-6);
  const auto rec = r.record();
  EXPECT_EQ(rec.tool, 2);
  EXPECT_FALSE(rec.length_known);
  EXPECT_NEAR(b.g54_z(), -2, 1e-12) << "no offset written";
}

TEST(ToolChangeRoutine, ASensorThatNeverTriggersFailsWithoutAlarm) {
  Bench b;
  ToolChangeConfig c = sensor_config();
  c.probe_x = 150;  // nothing there
  ToolChangeRoutine r(c, b.request(), std::nullopt);
  b.run(r);
  EXPECT_FALSE(r.succeeded());
  EXPECT_NE(r.failure().find("never triggered"), std::string::npos) << r.failure();
  EXPECT_TRUE(b.alarms.empty());
  EXPECT_EQ(r.record().tool, 1) << "it failed measuring the reference, before the mount";
}

TEST(ToolChangeRoutine, AnImplausibleLengthIsQuestionedAndADeclineChangesNothing) {
  Bench b;
  ToolChangeConfig c = plate_config();
  c.max_length_change = 5;
  ToolChangeRoutine r(c, b.request(), std::nullopt);
  b.run(r);
  EXPECT_FALSE(r.succeeded());
  ASSERT_EQ(b.prompts.size(), 2u);
  EXPECT_EQ(b.prompts[1].kind, PromptKind::Question);
  EXPECT_NEAR(b.g54_z(), -2, 1e-12);
  EXPECT_FALSE(r.record().length_known);

  Bench yes;
  yes.operator_action = [&yes](const ToolChangePrompt& p) {
    if (p.kind == PromptKind::MountTool) yes.m.request_mount(p.tool);
    return true;
  };
  ToolChangeRoutine accepted(c, yes.request(), std::nullopt);
  yes.run(accepted);
  EXPECT_TRUE(accepted.succeeded()) << accepted.failure();
  EXPECT_NEAR(yes.g54_z(), -2 + 7.3, 0.0015);
}

TEST(ToolChangeRoutine, AHoldStopsTheRoutineUntilCycleStart) {
  Bench b;
  ToolChangeRoutine r(plate_config(), b.request(), std::nullopt);
  bool held = false, resumed = false;
  std::size_t sent_at_hold = 0;
  b.run(r, 600, [&](double) {
    // During the first move: feed hold, five seconds, cycle start.
    if (!held && b.m.state() == cncsim::MachineState::Run) {
      b.m.receive("!");
      held = true;
      for (int i = 0; i < 100; ++i) {
        b.m.advance(0.05);
        if (auto st = parse_status_report(b.m.status_report())) r.on_status(*st);
      }
      sent_at_hold = b.sent.size();
      EXPECT_EQ(b.m.state_name(), "Hold:0");
      EXPECT_FALSE(r.take_line()) << "nothing more is sent while the machine holds";
      b.m.receive("~");
      resumed = true;
    }
  });
  EXPECT_TRUE(held && resumed);
  EXPECT_GT(b.sent.size(), sent_at_hold);
  EXPECT_TRUE(r.succeeded()) << r.failure();
  EXPECT_NEAR(b.g54_z(), -2 + 7.3, 0.0015);
}

TEST(ToolChangeRoutine, ManualWaitsForTheOperatorAndProbesNothing) {
  Bench b;
  ToolChangeConfig c = plate_config();
  c.method = ToolChangeMethod::Manual;
  b.operator_action = [&b](const ToolChangePrompt& p) {
    EXPECT_EQ(p.kind, PromptKind::ZeroManually);
    b.m.request_mount(p.tool);
    // The operator touches off: the new tip at work Z0 where the old one was.
    b.command("G10 L2 P1 Z5.3");
    return true;
  };
  ToolChangeRoutine r(c, b.request(), std::nullopt);
  b.run(r);
  EXPECT_TRUE(r.succeeded()) << r.failure();
  EXPECT_FALSE(b.sent_any("G91 G38"));
  EXPECT_TRUE(r.record().length_known);
  EXPECT_FALSE(r.reference()) << "a manual zero invalidates any reference";
}

#include "cncstream/gcode/tool_change_line.hpp"

TEST(ToolChangeLines, M6AndATWordBeforeM0AreChangesAPlainM0IsNot) {
  const std::vector<std::string> lines = {"G21 G90",  "T1",        "G0 Z5",  "M0",           // 3: a pause
                                          "(mount T2)", "T2",      "M0",                    // 6: a change to T2
                                          "G1 X1 F100", "T3 M6",   "M6",                    // 8: T3; 9: T3 again
                                          "T4",       "(note)",    "m00 (go)", "M06.5"};     // 12: T4
  const auto c = cncstream::gcode::find_tool_changes(lines);
  ASSERT_EQ(c.size(), 4u);
  EXPECT_EQ(c[0].index, 6u);
  EXPECT_EQ(c[0].tool, 2);
  EXPECT_EQ(c[0].note, "mount T2");
  EXPECT_EQ(c[1].index, 8u);
  EXPECT_EQ(c[1].tool, 3);
  EXPECT_EQ(c[2].index, 9u);
  EXPECT_EQ(c[2].tool, 3);
  EXPECT_EQ(c[3].index, 12u);
  EXPECT_EQ(c[3].tool, 4);
  EXPECT_EQ(cncstream::gcode::first_tool(lines), 1);
}

// Outside a job (ToolRoutineKind): the active work offset read with $G, no
// return to a program; the broken-bit check compares with the recorded
// trigger; a hold ends it (inside a job it waits through the job's hold).
TEST(ToolChangeRoutine, OutsideAJobMeasureThenTheCheckFindsAShorterBitAndAHoldEndsIt) {
  Bench b(bench_machine(30 - 1.2));  // T2: T1 broken 1.2 mm shorter
  ToolChangeRequest q = b.request(1, 1);
  q.in_job = false;
  q.kind = ToolRoutineKind::MeasureReference;
  ToolChangeRoutine measure(sensor_config(), q, std::nullopt);
  b.run(measure);
  ASSERT_TRUE(measure.succeeded()) << measure.failure();
  ASSERT_FALSE(b.sent.empty());
  EXPECT_EQ(b.sent[0], "$G");
  EXPECT_FALSE(b.sent_any("G10"));
  EXPECT_FALSE(b.sent_any("M3"));  // stays off: no program to go back to
  EXPECT_NEAR(b.m.machine_position().z, kSafeZ, 1e-6);
  ASSERT_TRUE(measure.reference() && measure.reference()->measured_trigger_z);
  EXPECT_NEAR(measure.reference()->offset_z, -2, 1e-9);
  EXPECT_EQ(measure.reference()->measured_tool, 1);

  q.kind = ToolRoutineKind::CheckLength;
  ToolChangeRoutine same(sensor_config(), q, measure.reference());
  b.run(same);
  ASSERT_TRUE(same.succeeded()) << same.failure();
  ASSERT_TRUE(same.length_difference());
  EXPECT_NEAR(*same.length_difference(), 0, 0.002);

  b.m.request_mount(2);  // the bit broke: 1.2 mm shorter, the routine still thinks T1
  ToolChangeRoutine broken(sensor_config(), q, measure.reference());
  b.run(broken);
  EXPECT_FALSE(broken.succeeded());
  EXPECT_NE(broken.failure().find("T1 is 1.200 mm shorter"), std::string::npos) << broken.failure();
  EXPECT_FALSE(broken.record().length_known);
  EXPECT_NEAR(b.g54_z(), -2, 1e-12) << "nothing written";

  // Another method than the measurement's, or nothing recorded: fails before anything is sent.
  const std::size_t sent = b.sent.size();
  ToolChangeConfig plate = plate_config();
  ToolChangeRoutine other(plate, q, measure.reference());
  other.start();
  EXPECT_TRUE(other.finished() && !other.succeeded());
  EXPECT_NE(other.failure().find("measured with the sensor"), std::string::npos) << other.failure();
  ToolChangeRoutine none(sensor_config(), q, std::nullopt);
  none.start();
  EXPECT_NE(none.failure().find("no measured length of T1"), std::string::npos) << none.failure();
  EXPECT_FALSE(none.take_line());
  EXPECT_EQ(b.sent.size(), sent);

  // A feed hold during its first move ends it: nothing more is sent.
  ToolChangeRoutine held(sensor_config(), q, measure.reference());
  bool hold_sent = false;
  b.run(held, 600, [&](double) {
    if (!hold_sent && b.m.state() == cncsim::MachineState::Run) {
      b.m.receive("!");
      hold_sent = true;
    }
  });
  EXPECT_TRUE(hold_sent);
  EXPECT_FALSE(held.succeeded());
  EXPECT_NE(held.failure().find("held"), std::string::npos) << held.failure();
}
