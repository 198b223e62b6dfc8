#include "job_run.hpp"

#include <algorithm>

namespace cncstream::jobs {

namespace {

// Reports closer together than this inside a stage are dropped: a grid of
// many tiles would otherwise call the callback thousands of times.
constexpr double kMinReportStep = 1e-3;

}  // namespace

void JobRun::stage(std::string_view name, double from, double to) {
  check();
  std::lock_guard lock(mutex_);
  stage_ = name;
  from_ = from;
  to_ = to;
  report(from);
}

void JobRun::within(double fraction) {
  check();
  if (!control_.progress) return;  // nobody listens: a checkpoint is only the stop check
  std::lock_guard lock(mutex_);
  report(from_ + (to_ - from_) * std::clamp(fraction, 0.0, 1.0));
}

cam::Checkpoint JobRun::checkpoint() {
  return [this](double fraction) { within(fraction); };
}

cam::Checkpoint JobRun::nested_checkpoint(double from, double to) {
  return [this, from, to](double fraction) { within(from + (to - from) * std::clamp(fraction, 0.0, 1.0)); };
}

JobControl JobRun::nested(double from, double to) {
  JobControl c;
  c.stop = control_.stop;
  c.progress = [this, from, to](std::string_view stage, double fraction) {
    if (stage == "done") return;
    std::lock_guard lock(mutex_);
    stage_ = stage;
    from_ = to_ = from + (to - from) * std::clamp(fraction, 0.0, 1.0);
    report(from_);
  };
  return c;
}

void JobRun::finish() {
  std::lock_guard lock(mutex_);
  stage_ = "done";
  report(1.0);
}

// Workers finish units in any order, so a fraction below the last one
// reported is dropped rather than sent backwards. Once a stop is requested
// nothing more is reported (the reporting thread throws at its next check).
void JobRun::report(double fraction) {
  if (!control_.progress || fraction < last_) return;
  if (stage_ != "done" && control_.stop.stop_requested()) return;
  const bool new_stage = stage_ != reported_stage_;
  if (!new_stage && (fraction == last_ || (fraction < 1.0 && fraction - last_ < kMinReportStep))) return;
  last_ = fraction;
  reported_stage_ = stage_;
  control_.progress(stage_, fraction);
}

}  // namespace cncstream::jobs
