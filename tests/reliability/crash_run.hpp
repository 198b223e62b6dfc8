#pragma once
// Crash at any moment: the real `cncstream` streams a finishing job (the
// plaque, a 40 x 30 mm corner) to the real `cncsim` through its pty and is
// killed with SIGKILL at moments drawn from a fixed seed (at a journaled
// line, or a time after it started, which also lands in identification and
// in a resume's preamble). After each kill the journal must open, `cncstream
// jobs` must list the job as interrupted with its last answered line, and
// `cncstream resume` continues it, until a resume completes. Optionally the
// simulator is killed instead once (the port vanishes): the streamer must
// say so, journal the job as disconnected, and a fresh simulator started
// from the saved state (its machined surface and tool position) finishes
// it. The machined surface must equal an uninterrupted run's.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace reliability {

struct CrashOptions {
  int kills = 3;
  std::uint64_t seed = 16;
  bool kill_simulator = false;  // the kill in the middle takes the simulator (SIGTERM: its port vanishes)
  std::filesystem::path dir;    // program, journals, results (the reference is kept for later runs)
  std::string sim_speed = "60";
};

struct KillRecord {
  std::string victim;       // "cncstream" or "cncsim"
  std::string moment;       // "line >= N" or "T s after start"
  std::int64_t job = 0;     // the newest journal job when it came
  std::string listed;       // the job's line in `cncstream jobs`
  long last_line = 0;       // last answered file line, journal
  long resumed_after = -1;  // the line the next resume continued after
};

struct CrashReport {
  std::vector<KillRecord> kills;
  int runs = 0;              // cncstream runs of the job (first + resumes)
  bool completed = false;    // the last resume completed the job
  std::size_t program_lines = 0;
  std::size_t nodes = 0;            // height-field nodes compared
  double max_height_diff_mm = -1;   // largest |final - reference|
  std::string reference_verify, final_verify;  // the simulator's verify at exit
  double seconds = 0;
  std::vector<std::string> problems;
};

CrashReport run_crash_resume(const CrashOptions& options);

}  // namespace reliability
