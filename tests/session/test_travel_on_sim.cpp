// A program larger than the machine's travel ($130-$132) is refused before
// its first line is sent; one that fits runs. Against the built-in simulator
// with a small machine (60 x 50 x 30 mm). The travel is trusted only where
// homing is on ($22): GRBL itself uses it only then, and a machine that never
// set it reports GRBL's default 200 mm whatever its size.
#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <thread>

#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/session/machine_session.hpp"
#include "support/run_until.hpp"
#include "cncstream/session/simulator_port.hpp"

using namespace cncstream::session;
using cncstream::protocol::JobMode;
using cncstream::protocol::JobOutcome;
using cncstream::protocol::MachineState;
namespace fs = std::filesystem;
using cncstream::test::run_until;

namespace {

fs::path travel_dir() {
  const auto d = fs::temp_directory_path() / ("cncstream_travel_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

// The work spans X 0..`x`, Y 0..40, Z -2..5.
JobInput travel_program(const std::string& x) {
  JobInput j;
  j.file = travel_dir() / ("x" + x + ".nc");
  j.lines = {"G21 G90", "G0 Z5", "G0 X0 Y0", "G1 Z-2 F600", "G1 X" + x + " Y40", "G0 Z5", "M2"};
  j.total_lines = static_cast<std::int64_t>(j.lines.size());
  return j;
}

// A 60 x 50 x 30 machine, homed when `homing` (it boots in alarm until $H).
struct SmallMachine {
  boost::asio::io_context io;
  std::shared_ptr<SimulatorPort> sim;
  std::unique_ptr<MachineSession> session;
  std::optional<JobOutcome> outcome;
  Subscription watch;

  explicit SmallMachine(bool homing) {
    const auto settings = travel_dir() / (homing ? "homing.settings" : "no_homing.settings");
    std::ofstream(settings) << "$130=60\n$131=50\n$132=30\n$22=" << (homing ? 1 : 0) << "\n";
    SimulatorOptions so;
    so.settings_file = settings.string();
    sim = std::make_shared<SimulatorPort>(so);
    MachineOptions o;
    o.name = "small";
    o.port = sim;
    o.profiles_dir = cncstream::protocol::default_profiles_dir();
    session = std::make_unique<MachineSession>(io, o);
    watch = session->subscribe([this](const SessionEvent& e) {
      if (e.kind == SessionEventKind::JobEnded) outcome = e.outcome;
    });
    session->open();
    EXPECT_TRUE(run_until(io, [&] { return session->ready(); }));
    if (homing) {
      EXPECT_TRUE(session->home());
      EXPECT_TRUE(run_until(io, [&] {
        const auto st = session->snapshot().status;
        return st && st->state == MachineState::Idle;
      })) << "the machine did not home";
    }
  }
  bool run_to_end() { return run_until(io, [&] { return outcome.has_value(); }); }
};

}  // namespace

TEST(TravelOnSim, AProgramThatFitsRuns) {
  SmallMachine m(true);
  const auto before = m.sim->lines_received();
  ASSERT_TRUE(m.session->start_job(travel_program("55")));
  ASSERT_TRUE(m.run_to_end());
  EXPECT_EQ(*m.outcome, JobOutcome::Completed);
  EXPECT_EQ(m.sim->lines_received() - before, 7u);
}

TEST(TravelOnSim, AProgramLargerThanTheTravelIsRefusedBeforeItsFirstLine) {
  // 6 inches written as mm would fit; taken as mm it spans 152.4 mm.
  SmallMachine m(true);
  const auto before = m.sim->lines_received();
  const JobInput job = travel_program("152.4");
  const auto r = m.session->start_job(job);
  ASSERT_FALSE(r);
  EXPECT_NE(r.reason.find(job.file.string()), std::string::npos) << r.reason;
  EXPECT_NE(r.reason.find("X: the program spans 152.4 mm (0 .. 152.4 as traced), the machine travels 60 mm ($130)"),
            std::string::npos) << r.reason;
  EXPECT_EQ(r.reason.find("Y:"), std::string::npos) << r.reason;
  EXPECT_NE(r.reason.find("25.4 times too large"), std::string::npos) << r.reason;
  m.io.run_for(std::chrono::milliseconds(200));
  EXPECT_EQ(m.sim->lines_received(), before) << "a line of the refused program reached the machine";
  EXPECT_FALSE(m.session->job_active());
}

TEST(TravelOnSim, CheckModeIsNotRefused) {
  // $C moves nothing: it reports the program's own errors.
  SmallMachine m(true);
  ASSERT_TRUE(m.session->start_job(travel_program("152.4"), JobMode::Check));
  ASSERT_TRUE(m.run_to_end());
  EXPECT_EQ(*m.outcome, JobOutcome::CheckPassed);
}

TEST(TravelOnSim, WithoutHomingTheTravelSettingsAreNotTrustedAndTheProgramRuns) {
  SmallMachine m(false);
  ASSERT_TRUE(m.session->start_job(travel_program("152.4")));
  ASSERT_TRUE(m.run_to_end());
  EXPECT_EQ(*m.outcome, JobOutcome::Completed);
}
