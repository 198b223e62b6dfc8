#pragma once
// Ctrl-C (SIGINT) and SIGTERM while a command computes in this process (a
// tool path, a selection, a plan, a grid): the first asks the job to stop
// through its stop token, so that it ends at its next checkpoint without
// writing its output; a second ends the process at once (its temporary file,
// named `<output>.part-PID-N`, may stay behind).
//
// The signal handler only counts and writes a byte to a pipe
// (async-signal-safe); a watcher thread reads it and requests the stop. One
// guard at a time; its destructor gives the signals back to what handled them
// before (a streaming session installs its own Ctrl-C handling afterwards).
#include <atomic>
#include <stop_token>
#include <thread>

namespace cncstream::app {

class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;

  std::stop_token token() const { return source_.get_token(); }
  bool interrupted() const { return source_.stop_requested(); }
  // The status a command interrupted by the first signal exits with:
  // 128 + its number (130 for SIGINT, 143 for SIGTERM).
  int exit_status() const;

 private:
  std::stop_source source_;
  int pipe_[2] = {-1, -1};
  std::thread watcher_;
};

}  // namespace cncstream::app
