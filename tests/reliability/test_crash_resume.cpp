// Crash at any moment, short: three kill -9 of the streamer, and one death
// of the simulator, each resumed from the journal to the same machined
// surface as an uninterrupted run (crash_run.hpp). tools/crash_resume.sh runs
// the same tests with twenty kills (CNCCRASH_KILLS, CNCCRASH_SEED).
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "child.hpp"
#include "cncstream/transport/journal.hpp"
#include "crash_run.hpp"
#include "sim/pty_process.hpp"

namespace {

namespace fs = std::filesystem;

// The surfaces agree to the height field's float precision: re-cut moves
// sweep the same cutter along the same path, and a resume's plunge ends on it.
constexpr double kSurfaceTolerance = 1e-4;  // mm

int env_or(const char* name, int fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::atoi(v) : fallback;
}

fs::path work_dir() { return fs::temp_directory_path() / ("cncstream_crash_" + std::to_string(::getpid())); }

// The program and the uninterrupted run are shared by the tests; the folder goes at the end.
class CrashDir : public ::testing::Environment {
 public:
  void TearDown() override { fs::remove_all(work_dir()); }
};
const auto* const kCrashDir = ::testing::AddGlobalTestEnvironment(new CrashDir);

void print(const char* what, const reliability::CrashReport& r) {
  std::printf("crash: %s: %zu-line job, %d cncstream runs, %.1f s\n", what, r.program_lines, r.runs, r.seconds);
  for (std::size_t i = 0; i < r.kills.size(); ++i) {
    const auto& k = r.kills[i];
    std::printf("crash: kill %zu of %s at %s: journal job %lld, last answered %ld; listed as |%s|; resumed after line %ld\n",
                i + 1, k.victim.c_str(), k.moment.c_str(), static_cast<long long>(k.job), k.last_line, k.listed.c_str(),
                k.resumed_after);
  }
  std::printf("crash: completed %s; surface vs uninterrupted run: %zu nodes, largest difference %.6f mm\n",
              r.completed ? "yes" : "NO", r.nodes, r.max_height_diff_mm);
  // The verify's first lines (nodes, largest gouge, largest excess) on one line.
  auto brief = [](std::string v) {
    std::size_t end = 0;
    for (int i = 0; i < 3 && end != std::string::npos; ++i) end = v.find('\n', end + (i ? 1 : 0));
    v = v.substr(0, end);
    std::replace(v.begin(), v.end(), '\n', ';');
    return v;
  };
  std::printf("crash: uninterrupted verify: %s\ncrash: final verify:         %s\n", brief(r.reference_verify).c_str(),
              brief(r.final_verify).c_str());
}

void expect_sound(const reliability::CrashReport& r, int kills) {
  std::string problems;
  for (const auto& p : r.problems) problems += p + "\n";
  EXPECT_TRUE(r.problems.empty()) << problems;
  EXPECT_TRUE(r.completed);
  // Every kill landed, but perhaps the last: the job may complete in the instant before it.
  int landed = 0;
  for (const auto& k : r.kills)
    if (k.moment.find("completed") == std::string::npos) ++landed;
  EXPECT_GE(landed, kills - 1);
  ASSERT_GT(r.nodes, 0u);
  EXPECT_LE(r.max_height_diff_mm, kSurfaceTolerance);
  EXPECT_FALSE(r.final_verify.empty());
}

}  // namespace

TEST(CrashResume, StreamerKilledAtRandomMomentsResumesToTheSameSurface) {
  reliability::CrashOptions o;
  o.kills = env_or("CNCCRASH_KILLS", 3);
  o.seed = static_cast<std::uint64_t>(env_or("CNCCRASH_SEED", 16));
  o.dir = work_dir();
  const auto r = reliability::run_crash_resume(o);
  print("kill -9 of cncstream", r);
  expect_sound(r, o.kills);
}

TEST(CrashResume, SimulatorKilledMidJobResumesOnAFreshOne) {
  reliability::CrashOptions o;
  o.kills = 1;
  o.kill_simulator = true;
  o.seed = static_cast<std::uint64_t>(env_or("CNCCRASH_SEED", 16)) + 1;
  o.dir = work_dir();
  const auto r = reliability::run_crash_resume(o);
  print("the simulator killed", r);
  expect_sound(r, o.kills);
}

// At real speed the controller is still running the dead streamer's queued
// moves when the resume connects (a board that does not reset on open): the
// resume must wait for it, not take the old answers for its own. It used to,
// and the character count overflowed the controller's buffer.
TEST(CrashResume, AResumeWaitsForTheMovesTheDeadStreamerQueued) {
  namespace fs = std::filesystem;
  const fs::path dir = work_dir() / "busy";
  fs::create_directories(dir);
  const std::string bin = CNCSTREAM_BINARY_DIR;
  const fs::path prog = dir / "long_moves.nc";
  {
    std::ofstream f(prog);
    f << "G21 G90 G94\nG1 F500\n";
    for (int i = 0; i < 400; ++i) f << "X" << (i % 2 ? 0 : 40) << " Y" << i * 0.1 << "\n";  // 40 mm rows: 5 s each
  }
  const std::vector<std::string> env{"XDG_STATE_HOME=" + (dir / "state").string()};
  const std::string db = (dir / "busy.sqlite").string();
  simtest::SimProcess sim({"--strict", "--speed", "30"});
  {
    reliability::Child first(bin + "/cncstream", {prog.string(), sim.slave(), "--journal", db, "--yes"}, env,
                             dir / "first.log");
    // Killed once it has queued moves: with a full planner of 40 mm rows the controller runs for a while.
    cncstream::transport::Journal j(db);
    for (int i = 0; i < 3000; ++i) {
      const auto jobs = j.jobs(1);
      if (!jobs.empty())
        if (const auto p = j.last_progress(jobs[0].id); p && p->last_line >= 12) break;
      if (first.exited()) break;
      usleep(10000);  // polling the journal
    }
    ASSERT_FALSE(first.exited()) << first.output();
    first.kill9();
  }
  reliability::Child resume(bin + "/cncstream",
                            {"resume", "1", sim.slave(), "--journal", db, "--yes", "--dwell", "0", "--timeout", "12"}, env,
                            dir / "resume.log");
  ASSERT_TRUE(resume.wait(60));
  const std::string out = resume.output();
  EXPECT_NE(out.find("the controller is busy (Run)"), std::string::npos) << out;
  EXPECT_NE(out.find("controller: grbl-1.1,"), std::string::npos) << "identified, not the fallback subset\n" << out;
  EXPECT_EQ(out.find("ERROR at line"), std::string::npos) << out;
  EXPECT_NE(out.find("job started"), std::string::npos) << out;
  const int code = sim.stop();
  EXPECT_EQ(code, 0) << "the strict simulator saw its buffer overflow:\n" << sim.stderr_text();
  EXPECT_NE(sim.stderr_text().find(" 0 RX bytes dropped"), std::string::npos) << sim.stderr_text();
}
