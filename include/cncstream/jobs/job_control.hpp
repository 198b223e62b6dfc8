#pragma once
// How a job runs, apart from what it computes: a stop request, progress
// reports and a thread limit. The jobs (tool path, selection, plan, resume
// planning) take plain parameters and return results, print nothing and may
// run on any thread, a daemon's worker included; nothing here changes what
// they compute.
#include <functional>
#include <stdexcept>
#include <stop_token>
#include <string_view>

namespace cncstream::jobs {

// Thrown by a job whose stop was requested, at its next checkpoint (between
// stages and between units of work inside the long ones). A cancelled job
// leaves no output file that looks complete: files are written under a
// temporary name and renamed once whole.
class Cancelled : public std::runtime_error {
 public:
  Cancelled() : std::runtime_error("job cancelled") {}
};

// `stage` names what the job is doing ("load", "tool path", ...); `fraction`
// is of the whole job, 0..1, and never decreases. A job that completes ends
// with ("done", 1).
using ProgressCallback = std::function<void(std::string_view stage, double fraction)>;

struct JobControl {
  std::stop_token stop;       // a stop requested on its source cancels the job
  ProgressCallback progress;  // called under the job's lock, from the calling thread or a worker: keep it short
  // 0: the job's parallel loops run in the caller's oneTBB task arena (the
  // shared pool of all cores, shared with any other job computing at once);
  // n: the whole job runs in a task arena of n slots.
  unsigned threads = 0;
  // A warning about the job's input (a part in the wrong units, ...), one
  // sentence, before the work it concerns; the job goes on.
  std::function<void(std::string_view)> warn;
};

}  // namespace cncstream::jobs
