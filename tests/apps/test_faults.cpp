// Each simulator fault through the real program: a clear report, a journal
// that agrees with it (outcome + lines answered), and nothing sent after the
// job stopped.
#include <gtest/gtest.h>

#include <fstream>
#include <cstdlib>

#include "app_run.hpp"
#include "cncstream/transport/journal.hpp"

using namespace apptest;
using cncstream::transport::Journal;

namespace {

// 606 lines: header, 600 short cutting moves, footer.
std::string short_program() {
  const auto p = temp_dir() / "short.nc";
  if (fs::exists(p)) return p.string();
  std::ofstream f(p);
  f << "G21 G90 G94\nG0 Z5\nM3 S10000\n";
  for (int i = 0; i < 600; ++i) f << "G1 X" << (i % 50) * 0.7 << " Y" << (i / 50) * 0.9 << " Z-1 F3000\n";
  f << "G0 Z5\nM5\nM2\n";
  return p.string();
}

long number_after(const std::string& text, const std::string& key) {
  const auto at = text.find(key);
  if (at == std::string::npos) return -1;
  return std::stol(text.substr(at + key.size()));
}

struct Outcome {
  AppRun run;
  std::string journal_outcome;
  long journal_last_line = -1;
  long sim_received = -1;
  long reported_last_line = -1;
  long journal_rows = -1;
};

Outcome run_with(std::vector<std::string> extra) {
  const auto db = (temp_dir() / ("faults" + std::to_string(::rand()) + ".sqlite")).string();
  std::vector<std::string> args{short_program(), "sim", "--journal", db, "--timeout", "20", "--no-sim-verify"};
  args.insert(args.end(), extra.begin(), extra.end());
  Outcome o;
  o.run = run_cncstream(args);
  Journal j(db);
  const auto jobs = j.jobs();
  EXPECT_EQ(jobs.size(), 1u) << "exactly one job, never an automatic second one";
  if (!jobs.empty()) {
    o.journal_outcome = jobs[0].outcome.value_or("interrupted");
    o.journal_rows = static_cast<long>(j.progress_count(jobs[0].id));
    if (const auto p = j.last_progress(jobs[0].id)) {
      o.journal_last_line = p->last_line;
      // Once the job has ended nothing more is journaled: the end row is last.
      EXPECT_EQ(p->reason, "end") << o.run.out;
    }
  }
  o.sim_received = number_after(o.run.out, "sim: ");
  o.reported_last_line = number_after(o.run.out, "last answered file line ");
  return o;
}

}  // namespace

TEST(Faults, InjectedErrorStopsTheJobWithoutAlarmAndSendsNothingMore) {
  const auto o = run_with({"--sim-error-at", "100:20"});
  EXPECT_EQ(o.run.code, 1) << o.run.out;
  EXPECT_TRUE(o.run.has("error:20 (Unsupported command)")) << o.run.out;
  EXPECT_TRUE(o.run.has("no terminal to decide: stopping the job")) << o.run.out;
  EXPECT_FALSE(o.run.has("ALARM")) << o.run.out;
  EXPECT_EQ(o.journal_outcome, "error");
  EXPECT_EQ(o.journal_last_line, o.reported_last_line);
  // The 100th line received is file line 98 ($$ and $I came first); at most
  // one RX buffer of lines (127 bytes, ~25 bytes each) was in flight then.
  EXPECT_LE(o.sim_received, 100 + 6) << o.run.out;
  EXPECT_GE(o.reported_last_line, 97);
}

TEST(Faults, AlarmEndsTheJobWithAdvice) {
  const auto o = run_with({"--sim-alarm-at", "100:1"});
  EXPECT_EQ(o.run.code, 1) << o.run.out;
  EXPECT_TRUE(o.run.has("ALARM:1 (Hard limit)")) << o.run.out;
  EXPECT_TRUE(o.run.has("re-home")) << o.run.out;
  EXPECT_EQ(o.journal_outcome, "alarm");
  EXPECT_EQ(o.journal_last_line, o.reported_last_line);
  EXPECT_LE(o.sim_received, 100 + 6) << o.run.out;
  // The alarm came with received line 100 (file line 98); the lines behind it
  // were refused (error:9) and count neither as answered nor as new errors.
  EXPECT_LE(o.reported_last_line, 98) << o.run.out;
  EXPECT_FALSE(o.run.has("ERROR at line")) << o.run.out;
}

TEST(Faults, DroppedAndCorruptedBytesAreReportedAsLineErrors) {
  for (const char* flag : {"--sim-drop-every", "--sim-corrupt-every"}) {
    const auto o = run_with({flag, "900"});
    EXPECT_EQ(o.run.code, 1) << flag << "\n" << o.run.out;
    EXPECT_TRUE(o.run.has("ERROR at line")) << o.run.out;
    EXPECT_EQ(o.journal_outcome, "error") << flag;
    EXPECT_EQ(o.journal_last_line, o.reported_last_line) << flag;
    // Nothing after the stop: received = $$ + $I + file lines up to the last
    // answered one + at most one RX buffer of lines in flight.
    EXPECT_LE(o.sim_received, o.reported_last_line + 2 + 6) << o.run.out;
    EXPECT_LT(o.reported_last_line, 600) << o.run.out;
  }
}

TEST(Faults, StallIsRiddenOutAndTheJobCompletes) {
  const auto o = run_with({"--sim-stall-at", "100:1.5"});
  EXPECT_EQ(o.run.code, 0) << o.run.out;
  EXPECT_EQ(o.journal_outcome, "completed");
  EXPECT_EQ(o.journal_last_line, 606);
  // Rows come every 0.1 s at most (plus one per event), not one per line:
  // each is an fsync, and one per line would make the journal the bottleneck.
  EXPECT_LT(o.journal_rows, 100) << o.run.out;
}

TEST(Faults, VanishingPortIsADisconnectRecordedAtTheLastAnsweredLineAndNeverResumed) {
  const auto o = run_with({"--sim-vanish-after", "200"});
  EXPECT_EQ(o.run.code, 1) << o.run.out;
  EXPECT_TRUE(o.run.has("outcome: disconnected")) << o.run.out;
  EXPECT_TRUE(o.run.has("nothing more will be sent")) << o.run.out;
  EXPECT_TRUE(o.run.has("cncstream resume 1 PORT")) << o.run.out;
  EXPECT_EQ(o.journal_outcome, "disconnected");
  // 200 answers: $$, $I and 198 file lines.
  EXPECT_EQ(o.reported_last_line, 198) << o.run.out;
  EXPECT_EQ(o.journal_last_line, 198);
}

TEST(Faults, CheckModeReportsEveryErrorWithoutMoving) {
  const auto bad = temp_dir() / "bad.nc";
  {
    std::ofstream f(bad);
    f << "G21 G90\nG1 X1 Y1\nG0 Z5\nG5 X1\nG0 X2\nM2\n";  // line 2: no feed; line 4: unsupported
  }
  const auto db = (temp_dir() / "check.sqlite").string();
  // --check: every error with its line, the pass runs to the end, nothing moves.
  const auto r = run_cncstream({bad.string(), "sim", "--check", "--journal", db, "--timeout", "20"});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("outcome: check-failed")) << r.out;
  EXPECT_TRUE(r.has("check: line 2 'G1X1Y1': error:22")) << r.out;
  EXPECT_TRUE(r.has("check: line 4 'G5X1': error:20")) << r.out;
  EXPECT_FALSE(r.has("stopping the job")) << r.out;
  EXPECT_FALSE(r.has("unexpectedly")) << r.out;
  EXPECT_TRUE(r.has("final position MPos 0.000,0.000,0.000")) << r.out;
  // --check-only on a good file: passes, moves nothing.
  const auto only = run_cncstream({short_program(), "sim", "--check-only", "--journal", db, "--timeout", "20"});
  EXPECT_EQ(only.code, 0) << only.out;
  EXPECT_TRUE(only.has("outcome: check-passed")) << only.out;
  EXPECT_TRUE(only.has("final position MPos 0.000,0.000,0.000")) << only.out;
  // --check on a good file: the pass, then the job itself.
  const auto good = run_cncstream({short_program(), "sim", "--check", "--journal", db, "--timeout", "20"});
  EXPECT_EQ(good.code, 0) << good.out;
  EXPECT_TRUE(good.has("check pass found no errors: streaming the job")) << good.out;
  EXPECT_TRUE(good.has("outcome: completed")) << good.out;
  EXPECT_TRUE(good.has("final position MPos 34.300,9.900,5.000")) << good.out;
  Journal j(db);
  const auto jobs = j.jobs();
  ASSERT_EQ(jobs.size(), 3u);
  EXPECT_EQ(jobs[0].mode, "check+run");
  EXPECT_EQ(j.last_progress(jobs[0].id)->last_line, 606);
  EXPECT_EQ(jobs[1].mode, "check");
  EXPECT_EQ(j.last_progress(jobs[1].id)->last_line, 0);  // a check pass is no progress to resume from
}
