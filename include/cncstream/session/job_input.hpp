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

}  // namespace cncstream::session
