#pragma once
// A command's computation run under the terminal: its jobs get a control
// whose stop is Ctrl-C/SIGTERM (interrupt.hpp) and whose progress is drawn on
// stderr (terminal_progress.hpp). A command that catches jobs::Cancelled
// ends with interrupted_exit(), naming what it did not write.
#include <string>

#include "cncstream/jobs/job_control.hpp"
#include "interrupt.hpp"
#include "terminal_progress.hpp"

namespace cncstream::app {

class LongJob {
 public:
  LongJob(ProgressMode mode, unsigned threads);
  // For the jobs this command runs (the same stop and line for all of them).
  jobs::JobControl control();
  // Before printing anything else on the terminal.
  void clear_progress() { progress_.clear(); }
  bool interrupted() const { return guard_.interrupted(); }
  // Clears the line, prints "cncstream: interrupted: <what>" on stderr and
  // returns the exit status (130 after Ctrl-C, 143 after SIGTERM).
  int interrupted_exit(const std::string& what);

 private:
  InterruptGuard guard_;
  TerminalProgress progress_;  // destroyed first: the line is cleared while the guard still holds
  unsigned threads_;
};

}  // namespace cncstream::app
