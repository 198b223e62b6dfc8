// A program larger than the machine's travel ($130-$132) is refused before
// its first line is sent; one that fits runs. Against the built-in simulator
// with a small machine (60 x 50 x 30 mm).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "cncstream/session/simulator_port.hpp"
#include "cncstream/session/stream_runner.hpp"

using namespace cncstream::session;
using cncstream::protocol::JobOutcome;
namespace fs = std::filesystem;

namespace {

fs::path temp_dir() {
  const auto d = fs::temp_directory_path() / ("cncstream_travel_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

fs::path write_file(const std::string& name, const std::string& text) {
  const auto p = temp_dir() / name;
  std::ofstream(p) << text;
  return p;
}

struct SmallMachine {
  std::shared_ptr<SimulatorPort> sim;
  RunnerOptions options;
  SmallMachine() {
    SimulatorOptions so;
    so.settings_file = write_file("small.settings", "$130=60\n$131=50\n$132=30\n").string();
    sim = std::make_shared<SimulatorPort>(so);
    options.machine_port = sim;
    options.profiles_dir = CNCSTREAM_SOURCE_DIR "/firmware-profiles";
    options.max_run_s = 30;
  }
};

// The work spans X 0..`x`, Y 0..40, Z -2..5.
std::string program(const std::string& x) {
  return "G21 G90\nG0 Z5\nG0 X0 Y0\nG1 Z-2 F600\nG1 X" + x + " Y40\nG0 Z5\nM2\n";
}

}  // namespace

TEST(TravelOnSim, AProgramThatFitsRuns) {
  SmallMachine m;
  StreamRunner runner(m.options);
  const RunResult r = runner.run(write_file("fits.nc", program("55")));
  EXPECT_EQ(r.outcome, JobOutcome::Completed) << r.message;
  m.sim->finish(true);
  EXPECT_GE(m.sim->lines_received(), 7u);
}

TEST(TravelOnSim, AProgramLargerThanTheTravelIsRefusedBeforeItsFirstLine) {
  // 6 inches written as mm would fit; taken as mm it spans 152.4 mm.
  SmallMachine m;
  StreamRunner runner(m.options);
  const auto file = write_file("too_large.nc", program("152.4"));
  std::string message;
  try {
    runner.run(file);
    ADD_FAILURE() << "the job was not refused";
  } catch (const std::invalid_argument& e) {
    message = e.what();
  }
  EXPECT_NE(message.find(file.string()), std::string::npos) << message;
  EXPECT_NE(message.find("X: the program spans 152.4 mm (0 .. 152.4 as traced), the machine travels 60 mm ($130)"),
            std::string::npos) << message;
  EXPECT_EQ(message.find("Y:"), std::string::npos) << message;
  EXPECT_NE(message.find("25.4 times too large"), std::string::npos) << message;
  const auto report = m.sim->finish(false);
  // The session's own lines only ($I, $$): none of the program's.
  EXPECT_LE(m.sim->lines_received(), 2u) << report.text;
}

TEST(TravelOnSim, CheckModeIsNotRefused) {
  // $C moves nothing: it reports the program's own errors.
  SmallMachine m;
  m.options.mode = cncstream::protocol::JobMode::Check;
  StreamRunner runner(m.options);
  const RunResult r = runner.run(write_file("check.nc", program("152.4")));
  EXPECT_EQ(r.outcome, JobOutcome::CheckPassed) << r.message;
  m.sim->finish(false);
}
