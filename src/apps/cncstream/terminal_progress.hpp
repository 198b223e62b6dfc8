#pragma once
// A long command's progress on stderr: one line rewritten in place (stage,
// percent, elapsed, time left), at most 10 times a second, cleared when the
// command prints something else or ends. Shown only when stderr is a terminal
// unless --progress says otherwise (tests force it on).
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>
#include <mutex>
#include <string_view>

#include "cncstream/jobs/progress_line.hpp"

namespace cncstream::app {

enum class ProgressMode { Auto, Always, Never };

// --progress auto|always|never (auto: when stderr is a terminal).
void add_progress_option(CLI::App* sub, ProgressMode& mode);

class TerminalProgress {
 public:
  // Draws on `out` when `mode` says so (Auto: `out` is a terminal).
  TerminalProgress(std::FILE* out, ProgressMode mode);
  ~TerminalProgress() { clear(); }
  TerminalProgress(const TerminalProgress&) = delete;
  TerminalProgress& operator=(const TerminalProgress&) = delete;

  // A job's progress callback (jobs::ProgressCallback): from any thread.
  void report(std::string_view stage, double fraction);
  // Erases the line (before other output, and at the end).
  void clear();
  bool enabled() const { return enabled_; }

 private:
  std::FILE* out_;
  bool enabled_;
  std::mutex mutex_;
  jobs::ProgressPacer pacer_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace cncstream::app
