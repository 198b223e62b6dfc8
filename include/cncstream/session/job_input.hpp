#pragma once
// A job to stream: the lines to send and, for each, the file line it stands
// for (so the journal and a later resume speak in file lines).
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "cncstream/gcode/program_extent.hpp"

namespace cncstream::session {

struct JobInput {
  std::filesystem::path file;      // journaled as the job's file
  std::string file_sha256;
  std::vector<std::string> lines;  // what to send, in order
  std::vector<long> source_lines;  // file line of each entry; empty: 1..n
  std::int64_t total_lines = 0;    // lines of the file
  std::int64_t resumed_from = 0;   // journal job this one resumes (0: none)
  std::int64_t from_line = 0;      // file line the resume continues after
  // The program's extent for the travel check, traced by a caller that has a
  // worker thread (the daemon: seconds for millions of lines would stall its
  // event loop); absent, start_job traces `lines` itself. A resume may give
  // the whole program's: its lines move within it.
  std::optional<gcode::ProgramExtent> extent;
};

// Reads a G-code file into a JobInput (hash, lines 1..n).
JobInput job_from_file(const std::filesystem::path& gcode_path);

// A program pause (M0) the machine holds on, and what the program says to
// the operator there (gcode::program_pause_note).
struct PauseAt {
  long line = 0;     // file line of the M0
  std::string note;  // empty: the program says nothing
};
// Where a job whose last answered file line is `answered` is paused, if the
// line it holds on is an M0: GRBL answers an M0 only once cycle start ends
// the pause, so that is the line after the last answered (a controller that
// answers first holds on the last answered one).
// `lines` and `source_lines` as in JobInput.
std::optional<PauseAt> pause_at(const std::vector<std::string>& lines, const std::vector<long>& source_lines,
                                long answered);
inline std::optional<PauseAt> pause_at(const JobInput& job, long answered) {
  return pause_at(job.lines, job.source_lines, answered);
}

}  // namespace cncstream::session
