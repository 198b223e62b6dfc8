#pragma once
// One job's side of its JobControl: stages with their share of the whole job,
// progress reports serialised and never decreasing, and the stop check that
// throws Cancelled. Private to the jobs layer.
#include <mutex>
#include <string>
#include <string_view>

#include "cncstream/cam/checkpoint.hpp"
#include "cncstream/jobs/job_control.hpp"

namespace cncstream::jobs {

class JobRun {
 public:
  explicit JobRun(const JobControl& control) : control_(control) {}
  JobRun(const JobRun&) = delete;
  JobRun& operator=(const JobRun&) = delete;

  // Throws Cancelled if a stop was requested.
  void check() const {
    if (control_.stop.stop_requested()) throw Cancelled();
  }
  // Starts the stage spanning [from, to] of the whole job: checks for a stop
  // and reports (name, from).
  void stage(std::string_view name, double from, double to);
  // Progress inside the current stage, fraction 0..1 of it; checks for a stop.
  // Thread-safe.
  void within(double fraction);
  // A cam-layer checkpoint doing within() for the current stage.
  cam::Checkpoint checkpoint();
  // The same for one part [from, to] of the current stage (two computations
  // in one stage).
  cam::Checkpoint nested_checkpoint(double from, double to);
  // The control for a job run inside this one (already in its thread limit):
  // the same stop, its stages reported as this job's, inside [from, to].
  JobControl nested(double from, double to);
  // Reports ("done", 1).
  void finish();

 private:
  void report(double fraction);  // with mutex_ held

  const JobControl& control_;
  std::mutex mutex_;
  std::string stage_, reported_stage_;
  double from_ = 0, to_ = 0;
  double last_ = -1;  // fraction last reported
};

}  // namespace cncstream::jobs
