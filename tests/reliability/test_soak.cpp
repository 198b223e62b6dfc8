// The soak under faults, short: ~30,000 numbered lines with every fault the
// simulator can inject, overrides and holds (soak_run.hpp). tools/soak.sh
// runs the same test with a million lines (CNCSOAK_LINES, CNCSOAK_FAULTS,
// CNCSOAK_SEED) and prints its figures.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "soak_run.hpp"

namespace {

std::size_t env_or(const char* name, std::size_t fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::strtoull(v, nullptr, 10) : fallback;
}

// Largest sample of a quarter of the run (q = 0..3).
std::size_t quarter_max(const std::vector<reliability::RssSample>& s, int q) {
  const std::size_t a = s.size() * static_cast<std::size_t>(q) / 4, b = s.size() * static_cast<std::size_t>(q + 1) / 4;
  std::size_t m = 0;
  for (std::size_t i = a; i < b; ++i) m = std::max(m, s[i].kib);
  return m;
}

}  // namespace

TEST(Soak, EveryLineRunsOnceUnderFaults) {
  reliability::SoakOptions o;
  o.lines = env_or("CNCSOAK_LINES", 30000);
  o.faults = env_or("CNCSOAK_FAULTS", 20);
  o.seed = env_or("CNCSOAK_SEED", 16);
  o.dir = std::filesystem::temp_directory_path() / ("cncstream_soak_" + std::to_string(::getpid()));
  const auto r = reliability::run_soak(o);
  std::filesystem::remove_all(o.dir);

  // The figures tools/soak.sh prints.
  std::printf("soak: %zu program lines, seed %llu, %zu jobs, %.1f s, %.0f lines/s (%zu lines answered)\n",
              r.program_lines, static_cast<unsigned long long>(o.seed), r.segments.size(), r.seconds,
              double(r.answered) / r.seconds, r.answered);
  std::printf("soak: ran %zu of %zu lines, %zu never; %zu runs again, within %zu lines resumes went back over\n",
              r.ran, r.program_lines, r.missing, r.ran_again, r.replay_window_lines);
  for (const auto& [kind, n] : r.faults) std::printf("soak: fault %-32s %zu\n", kind.c_str(), n);
  std::printf("soak: %zu override changes, %zu hold/resume cycles, %zu power cycles, %zu journal rows\n", r.overrides,
              r.holds, r.power_cycles, r.journal_rows);
  std::size_t max_kib = 0;
  for (const auto& s : r.rss) max_kib = std::max(max_kib, s.kib);
  ASSERT_GE(r.rss.size(), 8u);
  const std::size_t early = quarter_max(r.rss, 1), late = quarter_max(r.rss, 3);
  std::printf("soak: RSS start %zu KiB, end %zu KiB, max %zu KiB; largest of the 2nd quarter %zu, of the 4th %zu\n",
              r.rss.front().kib, r.rss.back().kib, max_kib, early, late);
  for (std::size_t i = 0; i < r.segments.size(); ++i) {
    const auto& s = r.segments[i];
    std::string first = s.report.substr(0, s.report.find('\n'));
    std::printf("soak: job %zu after line %ld: %-32s -> %-12s last answered %ld, %zu answered not run | %s\n", i + 1,
                s.from_line, s.fault.c_str(), s.outcome.c_str(), s.last_line, s.unexecuted_answered,
                first.substr(0, 150).c_str());
    if (!s.resume.empty()) std::printf("soak:   resumed: %s\n", s.resume.c_str());
  }
  for (const auto& w : r.warnings) std::printf("soak: streamer warning: %s\n", w.c_str());

  std::string problems;
  for (const auto& p : r.problems) problems += p + "\n";
  EXPECT_TRUE(r.problems.empty()) << problems;
  EXPECT_EQ(r.missing, 0u);
  EXPECT_EQ(r.ran, r.program_lines);
  EXPECT_LE(r.ran_again, r.replay_window_lines) << "lines ran again outside the resumes' windows";
  EXPECT_EQ(r.segments.back().outcome, "completed");
  // Every kind of fault took effect at least once, and the operator's actions.
  if (o.faults >= 10) {
    for (const char* kind : {"error:N answers", "alarms with a line", "bytes dropped", "bytes damaged", "lost links",
                             "limit switch (ALARM:1 mid-move)", "stalls"})
      EXPECT_GE(r.faults.at(kind), 1u) << kind;
    EXPECT_GE(r.overrides, 3u);
    EXPECT_GE(r.holds, 3u);
  }
  // Flat memory: the 4th quarter of the run grows no more than a bound over
  // the 2nd (the 1st holds the start-up and the first resume's allocations).
  EXPECT_LE(late, early + 4096) << "resident memory grew by " << (late - early) << " KiB";
}
