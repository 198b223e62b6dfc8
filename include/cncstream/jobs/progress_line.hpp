#pragma once
// A job's progress as one short line of text (stage, percent, elapsed time
// and, once it can be guessed, the time left), and how often a terminal may
// redraw it. Pure: the program that draws it decides where and whether.
#include <string>
#include <string_view>

namespace cncstream::jobs {

// "tool path  42 %  0:12 elapsed, about 0:17 left". The time left is shown
// once 2 % of the job and 1 s have passed (an earlier guess is noise);
// `fraction` is clamped to 0..1.
std::string progress_line(std::string_view stage, double fraction, double elapsed_s);

// At most one redraw per `min_interval_s` (10 a second by default), except
// the first one and the last one (fraction 1), so that a job's end is always
// seen. Not thread-safe: the caller serialises.
class ProgressPacer {
 public:
  explicit ProgressPacer(double min_interval_s = 0.1) : min_interval_s_(min_interval_s) {}
  bool should_draw(double now_s, double fraction);
  // The next report draws whatever the time (after the line was cleared).
  void reset() { drawn_ = false; }

 private:
  double min_interval_s_;
  bool drawn_ = false;
  double last_s_ = 0;
};

}  // namespace cncstream::jobs
