#include "cncstream/jobs/progress_line.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/core.h>

namespace cncstream::jobs {

namespace {

// "0:07", "12:34", "1:02:03".
std::string clock_text(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  if (s >= 3600) return fmt::format("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60);
  return fmt::format("{}:{:02}", s / 60, s % 60);
}

}  // namespace

std::string progress_line(std::string_view stage, double fraction, double elapsed_s) {
  const double f = std::isfinite(fraction) ? std::clamp(fraction, 0.0, 1.0) : 0.0;
  std::string line(stage);
  line.append(fmt::format("  {:3} %", static_cast<int>(std::floor(f * 100)))).append("  ").append(clock_text(elapsed_s)).append(" elapsed");
  if (f >= 0.02 && f < 1 && elapsed_s >= 1) line.append(", about ").append(clock_text(elapsed_s * (1 - f) / f)).append(" left");
  return line;
}

bool ProgressPacer::should_draw(double now_s, double fraction) {
  const bool due = !drawn_ || fraction >= 1 || now_s - last_s_ >= min_interval_s_;
  if (!due) return false;
  drawn_ = true;
  last_s_ = now_s;
  return true;
}

}  // namespace cncstream::jobs
