#pragma once
// The operator's live view of a job, as pure formatting: a JobView (state
// in) -> text (out). The terminal edge (live_panel.hpp) decides when and
// where to draw it. ETA comes from the motion-time estimate, not line counts.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "cncstream/protocol/status_report.hpp"

namespace cncstream::app {

struct JobView {
  std::string title;          // "plaque.nc -> sim (grbl-1.1)"
  std::string job_state;      // "running", "paused", "stopping", ...
  std::string machine_state;  // "Run", "Hold:0", ... ("" before the first report)
  std::optional<protocol::Axes> wpos, mpos;
  long line = 0;              // last answered file line
  long total_lines = 0;
  double elapsed_s = 0;
  std::optional<double> eta_s;
  std::optional<std::array<int, 3>> overrides;  // feed, rapid, spindle %
  std::optional<double> buffer_fill;            // 0..1 of the controller's RX buffer
  bool show_help = false;
};

// "0:07", "12:03", "1:02:03"; "--:--" for a negative or non-finite value.
std::string format_duration(double seconds);
// "[#####.....]" with `width` cells inside the brackets.
std::string format_progress_bar(double fraction, int width);
// Several lines, each ending in '\n', none wider than `width`.
std::string format_job_panel(const JobView& v, int width = 80);
// One line for logs (no TTY): "line 1200/5000 24.0 % | Run | elapsed 0:12 | ETA 0:38 | ...".
std::string format_job_line(const JobView& v);
const char* job_keys_help();

// Remaining time from the planner's estimate of when each file line's motion
// ends. Once enough of the job has run, the estimate is scaled by how fast
// the job actually went so far (overrides, a faster simulator, holds).
class EtaEstimator {
 public:
  EtaEstimator() = default;
  // end_by_line[k] = estimated seconds from the job start until the motion of
  // file line k (1-based; index 0 unused) is done; non-decreasing.
  explicit EtaEstimator(std::vector<double> end_by_line);
  double total() const { return end_.empty() ? 0 : end_.back(); }
  bool empty() const { return end_.empty(); }
  // Estimated seconds from the start until file line `line` is done (clamped
  // to the file's lines).
  double at_line(long line) const;
  std::optional<double> remaining(long last_answered_line, double elapsed_s) const;

 private:
  std::vector<double> end_;
};

}  // namespace cncstream::app
