#pragma once
// The soak under faults: a numbered program streamed by a machine session
// (the streamer cncstream uses, with its journal) to the simulator on a pty,
// while, at points drawn from a fixed seed, the simulator injects its faults
// and the "operator" changes overrides and holds and resumes. A fault that
// ends the job is answered as an operator would: stop after an error, unlock
// after an alarm, reconnect to a power-cycled controller after a lost link,
// then resume from the journal with the project's resume planner. The
// simulator says which numbered lines ran and how often; the soak checks
// that every line ran, that any line run twice lies where a resume chose to
// go back, that each fault ended in a report, that the journal agrees with
// what the simulator ran, and samples the process's resident memory.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace reliability {

struct SoakOptions {
  std::size_t lines = 30000;
  std::uint64_t seed = 16;
  std::size_t faults = 20;   // faults that end a job (the program ends the run when they are spent)
  std::filesystem::path dir;  // program file and journal
  double wait_limit_s = 60;   // longest any single wait may take (a hang fails instead of blocking)
};

// One job of the run: the fault planned for it and how it ended.
struct Segment {
  std::string fault;     // the fault scheduled to end it ("none": the rest of the program)
  std::string outcome;   // as journaled
  std::string report;    // what the operator was told (error, alarm, disconnect text)
  long from_line = 0;    // resumed after this file line (0: from the start)
  long last_line = 0;    // last answered file line
  std::size_t unexecuted_answered = 0;  // answered lines of this job the simulator did not run
  std::string resume;   // why the next job continues where it does (the resume planner's reason)
};

struct RssSample {
  std::size_t answered = 0;  // file lines answered so far in the run
  std::size_t kib = 0;
};

struct SoakReport {
  std::size_t program_lines = 0;
  std::size_t ran = 0;          // distinct numbered lines the simulator ran
  std::size_t missing = 0;      // numbered lines that never ran
  std::size_t ran_again = 0;    // runs beyond the first, all inside resume windows if nothing is wrong
  std::size_t replay_window_lines = 0;  // lines resumes chose to go back over
  std::size_t answered = 0;     // file lines answered, over all jobs
  double seconds = 0;
  std::vector<Segment> segments;
  std::map<std::string, std::size_t> faults;  // injected, by kind (as the simulator applied them)
  std::size_t overrides = 0, holds = 0, power_cycles = 0;
  std::size_t journal_rows = 0;
  std::vector<RssSample> rss;
  std::vector<std::string> problems;  // broken invariants, each with its context
  std::vector<std::string> warnings;  // what the streamer warned about (stale answers...)
};

SoakReport run_soak(const SoakOptions& options);

// Resident set of this process, KiB (/proc/self/statm).
std::size_t resident_kib();

}  // namespace reliability
