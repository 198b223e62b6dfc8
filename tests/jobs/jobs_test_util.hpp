#pragma once
// Shared by the jobs tests: the example part, a private temporary folder, and
// a progress recorder.
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "cncstream/jobs/job_control.hpp"

namespace jobstest {

namespace fs = std::filesystem;

inline std::string plaque() { return std::string(CNCSTREAM_SOURCE_DIR) + "/examples/plaque.stl"; }

inline fs::path temp_dir(const std::string& name) {
  const auto d = fs::temp_directory_path() / ("cncstream_jobs_" + std::to_string(::getpid())) / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// The names in `dir`, sorted: a written output must leave no temporary beside it.
inline std::vector<std::string> names_in(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

// Every progress report of a job, in the order the job made them.
struct ProgressLog {
  std::mutex mutex;
  std::vector<std::pair<std::string, double>> reports;
  cncstream::jobs::ProgressCallback callback() {
    return [this](std::string_view stage, double fraction) {
      std::lock_guard lock(mutex);
      reports.emplace_back(std::string(stage), fraction);
    };
  }
};

}  // namespace jobstest
