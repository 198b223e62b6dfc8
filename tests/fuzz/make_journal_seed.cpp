// A small, valid journal: one job, two progress rows (the journal fuzz
// target's seed, so it starts from a real database and damages it).
#include <filesystem>
#include <iostream>

#include "cncstream/transport/journal.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: make_journal_seed OUT.sqlite\n";
    return 2;
  }
  std::filesystem::remove(argv[1]);
  {
    cncstream::transport::Journal j(argv[1]);
    const auto id = j.begin_job("part.nc", "ab", "grbl-1.1", "/dev/ttyUSB0", "run", 100);
    cncstream::transport::ProgressRecord p;
    p.job_id = id;
    p.lines_ok = 10;
    p.last_line = 10;
    p.reason = "periodic";
    p.wco = std::array<double, 3>{1, 2, 3};
    j.record_progress(p);
    p.lines_ok = 20;
    p.last_line = 20;
    p.reason = "stop";
    j.record_progress(p);
    j.end_job(id, "stopped", "operator stop");
  }
  // Fold the WAL into the file so the seed is one file.
  std::filesystem::remove(std::string(argv[1]) + "-shm");
  return 0;
}
