// The tool-change method `controller` (grblHAL's own, $341=0) through a
// machine session against the built-in simulator's grblHAL personality: the
// M6 goes to the controller, which enters its Tool state; the session
// acknowledges it (0xA3), the operator jogs and zeroes Z at the prompt
// (probing is refused there, as grblHAL answers G38.x with error:40),
// confirms, cycle start ends the change and the job goes on. Refused on
// GRBL 1.1 and with $341=4; a lost link in the Tool state ends the job with
// the tool's length unknown.
#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>

#include <filesystem>
#include <fstream>

#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/protocol/tool_change.hpp"
#include "cncstream/session/machine_session.hpp"
#include "cncstream/session/simulator_port.hpp"
#include "support/run_until.hpp"

using namespace cncstream;
using namespace cncstream::session;
using cncstream::test::run_until;

namespace {

struct ControllerRig {
  boost::asio::io_context io;
  std::shared_ptr<SimulatorPort> sim;
  std::unique_ptr<MachineSession> session;
  Subscription watch;
  std::vector<protocol::ToolChangePrompt> prompts;
  std::optional<protocol::ToolChangeRecord> record;
  std::string record_text;
  std::optional<protocol::JobOutcome> outcome;
  std::optional<protocol::MachineState> state_at_prompt;

  explicit ControllerRig(cncsim::Firmware firmware, const std::string& settings_file = {}) {
    SimulatorOptions so;
    so.firmware = firmware;
    so.settings_file = settings_file;
    so.stick_outs = parse_sim_stick_outs("1=flat:6@30,2=flat:6@37.3");
    sim = std::make_shared<SimulatorPort>(so);
    MachineOptions o;
    o.name = "hal";
    o.port = sim;
    o.profiles_dir = protocol::default_profiles_dir();
    protocol::ToolChangeConfig tc;
    tc.method = protocol::ToolChangeMethod::Controller;
    tc.safe_z = 10;
    o.tool_change = tc;
    session = std::make_unique<MachineSession>(io, o);
    watch = session->subscribe([this](const SessionEvent& e) {
      if (e.kind == SessionEventKind::ToolChange) {
        if (e.tool_prompt) {
          prompts.push_back(*e.tool_prompt);
          if (const auto st = session->status()) state_at_prompt = st->state;
        }
        if (e.tool_record) {
          record = e.tool_record;
          record_text = e.text;
        }
      }
      if (e.kind == SessionEventKind::JobEnded) outcome = e.outcome;
    });
    session->open();
    EXPECT_TRUE(run_until(io, [&] { return session->ready() && session->settings().count(13); }));
  }

  // T1 cuts a line, T2 (M6) another.
  static JobInput job() {
    JobInput j;
    j.file = "change.nc";
    j.lines = {"G21 G90 G17 G94", "T1",         "G0 Z5",         "G0 X5 Y5",      "G1 Z-1 F300", "G1 X20 F600",
               "G0 Z5",           "(mount T2)", "T2",            "M6",            "G0 X30 Y5",   "G1 Z-1 F300",
               "G1 X40 F600",     "G0 Z5",      "M2"};
    j.total_lines = static_cast<std::int64_t>(j.lines.size());
    return j;
  }

  bool at_prompt() const { return !prompts.empty() && !record; }
  std::optional<protocol::StatusReport> status() const { return session->status(); }
};

std::filesystem::path settings_with_341(int mode) {
  const auto p = std::filesystem::temp_directory_path() / ("cncstream_hal_341_" + std::to_string(mode) + ".txt");
  std::ofstream(p) << "$341=" << mode << "\n";
  return p;
}

}  // namespace

TEST(ControllerToolChange, M6GoesToGrblHalOperatorJogsAndZeroesInTheToolStateAndTheJobGoesOn) {
  ControllerRig rig(cncsim::Firmware::GrblHal);
  ASSERT_EQ(rig.session->snapshot().profile, "grblhal");
  ASSERT_TRUE(rig.session->start_job(ControllerRig::job()));
  ASSERT_TRUE(run_until(rig.io, [&] { return rig.at_prompt() || rig.outcome; }, 120));
  ASSERT_FALSE(rig.outcome) << rig.record_text;
  ASSERT_EQ(rig.prompts.size(), 1u);
  EXPECT_EQ(rig.prompts[0].kind, protocol::PromptKind::ZeroManually);
  EXPECT_EQ(rig.prompts[0].tool, 2);
  // The controller is in its Tool state (the M6 went to it, acknowledged).
  ASSERT_TRUE(rig.state_at_prompt);
  EXPECT_EQ(*rig.state_at_prompt, protocol::MachineState::Tool);
  // grblHAL refuses G38.x there: the session says so before sending it.
  const auto probe = rig.session->probe_z();
  EXPECT_FALSE(probe);
  EXPECT_NE(probe.reason.find("error:40"), std::string::npos) << probe.reason;
  // The operator mounts T2 (7.3 mm longer), jogs down 3 mm and zeroes Z there.
  rig.sim->operator_mount(2);
  const double z_before = (*rig.status()->mpos)[2];
  const auto jog = rig.session->jog_step({0, 0, -1}, 3, 300);
  ASSERT_TRUE(jog) << jog.reason;
  ASSERT_TRUE(run_until(rig.io, [&] {
    const auto st = rig.status();
    return !rig.session->snapshot().jogging && st && st->state == protocol::MachineState::Tool &&
           std::fabs((*st->mpos)[2] - (z_before - 3)) < 1e-6;
  }));
  ASSERT_TRUE(rig.session->zero_axes("Z"));
  // Spindle and homing stay refused at the prompt.
  EXPECT_FALSE(rig.session->spindle(true));
  EXPECT_FALSE(rig.session->home());
  ASSERT_TRUE(rig.session->tool_change_confirm());
  ASSERT_TRUE(run_until(rig.io, [&] { return rig.outcome.has_value(); }, 120));
  EXPECT_EQ(*rig.outcome, protocol::JobOutcome::Completed) << rig.record_text;
  ASSERT_TRUE(rig.record);
  EXPECT_EQ(rig.record->tool, 2);
  EXPECT_EQ(rig.record->method, protocol::ToolChangeMethod::Controller);
  EXPECT_TRUE(rig.record->length_known) << rig.record_text;
  // The work offset the operator's zero made (G54 Z at the jogged-to machine Z), read back with $#.
  ASSERT_TRUE(rig.record->offset_z);
  EXPECT_NEAR(*rig.record->offset_z, z_before - 3, 0.0015) << rig.record_text;
  EXPECT_EQ(rig.session->snapshot().tool_in_spindle, 2);
  // The job went on after cycle start: its last move left work Z at 5.
  const auto st = rig.status();
  ASSERT_TRUE(st && st->wpos);
  EXPECT_NEAR((*st->wpos)[2], 5, 1e-6);
  EXPECT_EQ(st->state, protocol::MachineState::Idle);
}

TEST(ControllerToolChange, RefusedOnGrbl11AndWithGrblHalIgnoringM6) {
  {
    ControllerRig rig(cncsim::Firmware::Grbl11);
    const auto r = rig.session->start_job(ControllerRig::job());
    EXPECT_FALSE(r);
    EXPECT_NE(r.reason.find("GRBL 1.1 answers M6 with error:20"), std::string::npos) << r.reason;
    EXPECT_NE(r.reason.find("choose plate, sensor or manual"), std::string::npos) << r.reason;
    // A program without a tool change runs as before.
    JobInput plain;
    plain.file = "plain.nc";
    plain.lines = {"G21 G90", "G0 X1", "M2"};
    ASSERT_TRUE(rig.session->start_job(plain));
    ASSERT_TRUE(run_until(rig.io, [&] { return rig.outcome.has_value(); }, 60));
    EXPECT_EQ(*rig.outcome, protocol::JobOutcome::Completed);
  }
  {
    ControllerRig rig(cncsim::Firmware::GrblHal, settings_with_341(4).string());
    const auto r = rig.session->start_job(ControllerRig::job());
    EXPECT_FALSE(r);
    EXPECT_NE(r.reason.find("$341=4: the controller ignores M6"), std::string::npos) << r.reason;
  }
}

TEST(ControllerToolChange, ALostLinkInTheToolStateEndsTheJobWithTheLengthUnknown) {
  ControllerRig rig(cncsim::Firmware::GrblHal);
  ASSERT_TRUE(rig.session->start_job(ControllerRig::job()));
  ASSERT_TRUE(run_until(rig.io, [&] { return rig.at_prompt() || rig.outcome; }, 120));
  ASSERT_TRUE(rig.at_prompt());
  rig.sim->operator_mount(2);
  rig.sim->finish(false);  // the cable: the port goes away
  ASSERT_TRUE(run_until(rig.io, [&] { return rig.outcome.has_value() && rig.record.has_value(); }, 60));
  EXPECT_EQ(*rig.outcome, protocol::JobOutcome::Disconnected);
  EXPECT_FALSE(rig.record->length_known);
  EXPECT_EQ(rig.record->tool, 2) << "the operator was asked to mount T2: it may be in the spindle";
  EXPECT_NE(rig.record_text.find("the length of the tool in the spindle is unknown"), std::string::npos)
      << rig.record_text;
}

TEST(ControllerToolChange, ADeclineInTheToolStateStopsTheJobAndResetsTheControllerOutOfIt) {
  // grblHAL ignores a feed hold in its Tool state: the stop's reset follows at once.
  ControllerRig rig(cncsim::Firmware::GrblHal);
  ASSERT_TRUE(rig.session->start_job(ControllerRig::job()));
  ASSERT_TRUE(run_until(rig.io, [&] { return rig.at_prompt() || rig.outcome; }, 120));
  ASSERT_TRUE(rig.at_prompt());
  ASSERT_TRUE(rig.session->tool_change_decline());
  ASSERT_TRUE(run_until(rig.io, [&] { return rig.outcome.has_value(); }, 60));
  EXPECT_NE(*rig.outcome, protocol::JobOutcome::Completed);
  ASSERT_TRUE(rig.record);
  EXPECT_FALSE(rig.record->length_known);
  EXPECT_NE(rig.record_text.find("declined"), std::string::npos) << rig.record_text;
  ASSERT_TRUE(run_until(rig.io, [&] {
    const auto st = rig.status();
    return st && st->state == protocol::MachineState::Idle;
  }));
}
