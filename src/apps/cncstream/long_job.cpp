#include "long_job.hpp"

#include <cstdio>

#include "terminal_text.hpp"

namespace cncstream::app {

LongJob::LongJob(ProgressMode mode, unsigned threads) : progress_(stderr, mode), threads_(threads) {}

jobs::JobControl LongJob::control() {
  jobs::JobControl c;
  c.stop = guard_.token();
  c.threads = threads_;
  if (progress_.enabled()) c.progress = [this](std::string_view stage, double f) { progress_.report(stage, f); };
  c.warn = [this](std::string_view w) {
    progress_.clear();
    std::string msg = "cncstream: warning: ";
    msg.append(w).append("\n");
    put_text(stderr, msg);
  };
  return c;
}

int LongJob::interrupted_exit(const std::string& what) {
  progress_.clear();
  std::string msg = "cncstream: interrupted: ";
  msg.append(what).append("\n");
  put_text(stderr, msg);
  return guard_.exit_status();
}

}  // namespace cncstream::app
