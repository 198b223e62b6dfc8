// The tool routines outside a job (protocol/tool_change.hpp through
// MachineSession::run_tool_routine) against the built-in simulator with a
// tool table of unequal stick-outs and a tool-length sensor: measure the
// reference, change to a longer tool (the offset written and read back),
// check it, then a shorter (broken) bit fails the check; a sensor that never
// triggers stops within its travel.
#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>

#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/protocol/tool_change.hpp"
#include "cncstream/session/machine_session.hpp"
#include "cncstream/session/simulator_port.hpp"
#include "support/run_until.hpp"

using namespace cncstream;
using namespace cncstream::session;
using cncstream::test::run_until;

namespace {

constexpr double kSafeZ = 30;
constexpr double kTravel = 50;

// T1 30 mm stick-out (in the spindle at power-on), T2 7.3 mm longer, T3 the
// same T2 broken 1.2 mm shorter; a sensor at machine X-30 Y0 with its top at
// Z-10 (or none).
struct ToolRig {
  boost::asio::io_context io;
  std::shared_ptr<SimulatorPort> sim;
  std::unique_ptr<MachineSession> session;
  Subscription watch;
  std::vector<protocol::RoutinePrompt> prompts;
  std::optional<bool> ended_ok;
  std::string end_text;
  std::optional<protocol::ToolChangeRecord> record;
  bool auto_confirm = true;

  explicit ToolRig(bool sensor = true) {
    SimulatorOptions so;
    so.stick_outs = parse_sim_stick_outs("1=flat:6@30,2=flat:6@37.3,3=flat:6@36.1");
    if (sensor) so.tool_sensor = "-30,0,-10";
    sim = std::make_shared<SimulatorPort>(so);
    MachineOptions o;
    o.name = "tools";
    o.port = sim;
    o.profiles_dir = protocol::default_profiles_dir();
    session = std::make_unique<MachineSession>(io, o);
    watch = session->subscribe([this](const SessionEvent& e) {
      if (e.kind != SessionEventKind::Routine) return;
      if (e.routine_prompt) {
        prompts.push_back(*e.routine_prompt);
        // The simulated operator mounts what is asked, then confirms.
        if (e.routine_prompt->kind == protocol::PromptKind::MountTool) sim->operator_mount(e.routine_prompt->tool);
        if (auto_confirm) boost::asio::post(io, [this] { session->routine_confirm(); });
      } else if (e.routine_succeeded) {
        ended_ok = *e.routine_succeeded;
        end_text = e.text;
        record = e.tool_record;
      }
    });
    session->open();
    EXPECT_TRUE(run_until(io, [&] { return session->ready(); }));
  }

  static protocol::ToolChangeConfig sensor_config() {
    protocol::ToolChangeConfig c;
    c.method = protocol::ToolChangeMethod::Sensor;
    c.safe_z = kSafeZ;
    c.probe_x = -30;
    c.probe_y = 0;
    c.probe_travel = kTravel;
    return c;
  }

  // Runs one to its end; true when it succeeded.
  bool run(protocol::ToolRoutineKind kind, int tool = 0, double tolerance = 0.1) {
    ended_ok.reset();
    end_text.clear();
    record.reset();
    const auto started = session->run_tool_routine(sensor_config(), kind, tool, tolerance);
    EXPECT_TRUE(started.result) << started.result.reason;
    if (!started.result) return false;
    EXPECT_TRUE(run_until(io, [&] { return ended_ok.has_value(); }, 120));
    return ended_ok.value_or(false);
  }

  double g54_z() {
    // WCO = G54 (no G92, no TLO in these runs).
    const auto st = session->status();
    return st && st->wco ? (*st->wco)[2] : 1e9;
  }
  bool idle() {
    const auto st = session->status();
    return st && st->state == protocol::MachineState::Idle;
  }
};

}  // namespace

TEST(ToolRoutinesOnSim, MeasureChangeToALongerToolCheckThenABrokenBitFailsTheCheck) {
  ToolRig rig;
  ASSERT_TRUE(rig.session->set_tool_in_spindle(1));
  // Nothing measured yet: the check has nothing to compare with and is refused before anything moves.
  const auto nothing = rig.session->run_tool_routine(ToolRig::sensor_config(), protocol::ToolRoutineKind::CheckLength);
  EXPECT_FALSE(nothing.result);
  EXPECT_NE(nothing.result.reason.find("no measured length of T1"), std::string::npos) << nothing.result.reason;
  EXPECT_FALSE(rig.session->routine_active());

  // The operator zeroed T1 with G54 Z at -2.
  ASSERT_TRUE(rig.session->console("G10 L2 P1 Z-2"));
  ASSERT_TRUE(run_until(rig.io, [&] { return rig.idle() && std::fabs(rig.g54_z() + 2) < 1e-6; }));
  ASSERT_TRUE(rig.run(protocol::ToolRoutineKind::MeasureReference)) << rig.end_text;
  ASSERT_TRUE(rig.session->tool_reference());
  const auto ref = *rig.session->tool_reference();
  EXPECT_EQ(ref.tool, 1);
  EXPECT_NEAR(ref.offset_z, -2, 1e-6);
  EXPECT_NEAR(ref.trigger_z, -10, 0.01);  // T1's tip is the spindle's reference
  EXPECT_TRUE(rig.prompts.empty());       // nothing to ask

  // While a routine runs, nothing else moves the machine.
  rig.ended_ok.reset();
  const auto started = rig.session->run_tool_routine(ToolRig::sensor_config(), protocol::ToolRoutineKind::Change, 2);
  ASSERT_TRUE(started.result) << started.result.reason;
  EXPECT_FALSE(rig.session->jog_step({1, 0, 0}, 1, 100));
  EXPECT_FALSE(rig.session->console("G0 X0"));
  EXPECT_FALSE(rig.session->run_tool_routine(ToolRig::sensor_config(), protocol::ToolRoutineKind::CheckLength).result);
  ASSERT_TRUE(run_until(rig.io, [&] { return rig.ended_ok.has_value(); }, 120));
  ASSERT_TRUE(*rig.ended_ok) << rig.end_text;
  // T2 is 7.3 mm longer: the offset moves up by that, written and read back.
  ASSERT_EQ(rig.prompts.size(), 1u) << rig.end_text;
  EXPECT_EQ(rig.prompts[0].kind, protocol::PromptKind::MountTool);
  EXPECT_EQ(rig.prompts[0].tool, 2);
  ASSERT_TRUE(rig.record);
  EXPECT_EQ(rig.record->tool, 2);
  EXPECT_TRUE(rig.record->length_known);
  ASSERT_TRUE(rig.record->offset_z);
  EXPECT_NEAR(*rig.record->offset_z, -2 + 7.3, 0.002);
  EXPECT_EQ(rig.sim->mounted_tool(), 2);
  EXPECT_EQ(rig.session->snapshot().tool_in_spindle, 2);
  ASSERT_TRUE(run_until(rig.io, [&] { return rig.idle(); }));
  EXPECT_NEAR(rig.g54_z(), -2 + 7.3, 0.002);
  // It ends at the safe Z (machine), spindle off.
  EXPECT_NEAR((*rig.session->status()->mpos)[2], kSafeZ, 1e-3);

  // After roughing: T2 is as measured.
  ASSERT_TRUE(rig.run(protocol::ToolRoutineKind::CheckLength)) << rig.end_text;
  EXPECT_NE(rig.end_text.find("T2 is within 0.100 mm"), std::string::npos) << rig.end_text;
  EXPECT_TRUE(rig.record && rig.record->length_known);
  EXPECT_TRUE(started.routine);

  // The bit broke (1.2 mm shorter; the simulator mounts T3's length, the
  // session still says T2): the check fails, naming the difference, and the
  // offset is left alone; the reference stays for the next change.
  rig.sim->operator_mount(3);
  EXPECT_FALSE(rig.run(protocol::ToolRoutineKind::CheckLength));
  EXPECT_NE(rig.end_text.find("T2 is 1.200 mm shorter"), std::string::npos) << rig.end_text;
  EXPECT_NE(rig.end_text.find("length of the tool in the spindle is unknown"), std::string::npos) << rig.end_text;
  ASSERT_TRUE(rig.record);
  EXPECT_FALSE(rig.record->length_known);
  EXPECT_NEAR(rig.g54_z(), -2 + 7.3, 0.002);
  ASSERT_TRUE(rig.session->tool_reference());
  EXPECT_EQ(rig.session->tool_reference()->tool, 1);
  // A re-zero forgets the reference: the check has nothing to compare with again.
  ASSERT_TRUE(rig.session->zero_axes("Z"));
  EXPECT_FALSE(rig.session->tool_reference());
  EXPECT_FALSE(rig.session->run_tool_routine(ToolRig::sensor_config(), protocol::ToolRoutineKind::CheckLength).result);
}

TEST(ToolRoutinesOnSim, ASensorThatNeverTriggersStopsWithinItsTravel) {
  ToolRig rig(false);
  ASSERT_TRUE(rig.session->set_tool_in_spindle(1));
  EXPECT_FALSE(rig.run(protocol::ToolRoutineKind::MeasureReference));
  EXPECT_NE(rig.end_text.find("never triggered within 50.000 mm"), std::string::npos) << rig.end_text;
  EXPECT_FALSE(rig.session->tool_reference());
  // G38.3 from the safe Z: down by the travel at most, and nothing after it.
  ASSERT_TRUE(run_until(rig.io, [&] {
    const auto st = rig.session->status();
    return rig.idle() && st->mpos && (*st->mpos)[2] < kSafeZ - kTravel + 1;
  }, 20)) << rig.end_text;
  EXPECT_NEAR((*rig.session->status()->mpos)[2], kSafeZ - kTravel, 0.01) << rig.end_text;
  EXPECT_FALSE(rig.session->in_alarm());
}

TEST(ToolRoutinesOnSim, AManualChangeGivesTheMachineToTheOperatorAtItsPromptButNoHomingOrSpindle) {
  ToolRig rig;
  rig.auto_confirm = false;
  ASSERT_TRUE(rig.session->set_tool_in_spindle(1));
  auto cfg = ToolRig::sensor_config();
  cfg.method = protocol::ToolChangeMethod::Manual;
  // Manual measures nothing: measure and check are refused before anything moves.
  EXPECT_FALSE(rig.session->run_tool_routine(cfg, protocol::ToolRoutineKind::MeasureReference).result);
  const auto started = rig.session->run_tool_routine(cfg, protocol::ToolRoutineKind::Change, 2);
  ASSERT_TRUE(started.result) << started.result.reason;
  ASSERT_TRUE(run_until(rig.io, [&] { return !rig.prompts.empty(); }, 60));
  EXPECT_EQ(rig.prompts[0].kind, protocol::PromptKind::ZeroManually);
  // The operator's turn: a jog down, zero Z there; no homing, no spindle, no job, no other routine.
  ASSERT_TRUE(rig.session->jog_step({0, 0, -1}, 5, 500)) << "jogging works at the prompt";
  EXPECT_FALSE(rig.session->routine_confirm()) << "not while the jog runs";
  ASSERT_TRUE(run_until(rig.io, [&] { return !rig.session->snapshot().jogging && rig.idle(); }, 30));
  EXPECT_NEAR((*rig.session->status()->mpos)[2], kSafeZ - 5, 0.01);
  ASSERT_TRUE(rig.session->zero_axes("Z"));
  EXPECT_FALSE(rig.session->console("$H"));
  EXPECT_FALSE(rig.session->home());
  EXPECT_FALSE(rig.session->spindle(true));
  EXPECT_FALSE(rig.session->run_tool_routine(ToolRig::sensor_config(), protocol::ToolRoutineKind::CheckLength).result);
  ASSERT_TRUE(run_until(rig.io, [&] { return rig.idle(); }, 30));
  ASSERT_TRUE(rig.session->routine_confirm());
  ASSERT_TRUE(run_until(rig.io, [&] { return rig.ended_ok.has_value(); }, 60));
  EXPECT_TRUE(*rig.ended_ok) << rig.end_text;
  EXPECT_EQ(rig.session->snapshot().tool_in_spindle, 2);
  EXPECT_FALSE(rig.session->tool_reference()) << "a manual zero: no reference";
  // After it the machine is the operator's again, with the routine's rules gone.
  EXPECT_FALSE(rig.session->jog_step({0, 0, 1}, 1, 500).reason.find("running") != std::string::npos);
}
