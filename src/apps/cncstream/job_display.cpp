#include "job_display.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace cncstream::app {

std::string format_duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "--:--";
  const long t = std::lround(seconds);
  if (t >= 3600) return fmt::format("{}:{:02}:{:02}", t / 3600, (t / 60) % 60, t % 60);
  return fmt::format("{}:{:02}", t / 60, t % 60);
}

std::string format_progress_bar(double fraction, int width) {
  if (!std::isfinite(fraction)) fraction = 0;
  fraction = std::clamp(fraction, 0.0, 1.0);
  const int full = static_cast<int>(std::floor(fraction * width + 1e-9));
  std::string bar;
  bar.reserve(static_cast<std::size_t>(width) + 2);
  bar.push_back('[');
  bar.append(static_cast<std::size_t>(full), '#');
  bar.append(static_cast<std::size_t>(std::max(0, width - full)), '.');
  bar.push_back(']');
  return bar;
}

namespace {

std::string axes(const char* name, const std::optional<protocol::Axes>& a) {
  if (!a) return fmt::format("{} X{:>9} Y{:>9} Z{:>9}", name, "-", "-", "-");
  return fmt::format("{} X{:9.3f} Y{:9.3f} Z{:9.3f}", name, (*a)[0], (*a)[1], (*a)[2]);
}

double fraction(const JobView& v) { return v.total_lines > 0 ? double(v.line) / double(v.total_lines) : 0.0; }

std::string fit(std::string s, int width) {
  if (width > 3 && static_cast<int>(s.size()) > width) s = s.substr(0, static_cast<std::size_t>(width - 3)) + "...";
  return s;
}

std::string overrides_text(const JobView& v) {
  if (!v.overrides) return "Ov feed - rapid - spindle -";
  const auto& o = *v.overrides;
  return "Ov feed " + std::to_string(o[0]) + "% rapid " + std::to_string(o[1]) + "% spindle " + std::to_string(o[2]) + "%";
}

std::string buffer_text(const JobView& v) {
  if (!v.buffer_fill) return "buffer -";
  return fmt::format("buffer {:3.0f} %", 100.0 * std::clamp(*v.buffer_fill, 0.0, 1.0));
}

}  // namespace

const char* job_keys_help() {
  return "keys: space hold/resume | s stop (hold, reset) | +/- feed 10% | ]/[ feed 1% | 0 feed 100% | "
         ">/< spindle 10% | 1/2/3 rapid 100/50/25% | ? or h help | Ctrl-C stop\n"
         "arrows, PgUp/PgDn: no jogging while a job runs (refused); `cncstream jog PORT` jogs, and there "
         "+/- set the jog feed, 0 zeroes, 1-4 the step, s is safe Z and h homes";
}

std::string format_job_panel(const JobView& v, int width) {
  std::ostringstream o;
  o << fit(v.title + "  " + v.job_state + (v.show_help ? "" : "   (? for keys)"), width) << "\n";
  o << fit("state " + (v.machine_state.empty() ? std::string("-") : v.machine_state), width) << "\n";
  o << fit(axes("WPos", v.wpos) + "   " + axes("MPos", v.mpos), width) << "\n";
  const std::string pct = fmt::format("{:5.1f} %", 100.0 * fraction(v));
  o << fit("line " + std::to_string(v.line) + "/" + std::to_string(v.total_lines) + " " +
               format_progress_bar(fraction(v), 30) + " " + pct,
           width)
    << "\n";
  o << fit("elapsed " + format_duration(v.elapsed_s) + "   ETA " + (v.eta_s ? format_duration(*v.eta_s) : "--:--") +
               "   " + overrides_text(v) + "   " + buffer_text(v),
           width)
    << "\n";
  if (v.show_help) {
    std::istringstream help(job_keys_help());
    for (std::string line; std::getline(help, line);) o << fit(line, width) << "\n";
  }
  return o.str();
}

std::string format_job_line(const JobView& v) {
  const std::string pct = fmt::format("{:.1f} %", 100.0 * fraction(v));
  std::ostringstream o;
  o << "line " << v.line << "/" << v.total_lines << " " << pct << " | " << v.job_state << " | "
    << (v.machine_state.empty() ? "-" : v.machine_state) << " | elapsed " << format_duration(v.elapsed_s) << " | ETA "
    << (v.eta_s ? format_duration(*v.eta_s) : "--:--");
  if (v.wpos) {
    o << fmt::format(" | WPos {:.3f},{:.3f},{:.3f}", (*v.wpos)[0], (*v.wpos)[1], (*v.wpos)[2]);
  }
  o << " | " << overrides_text(v) << " | " << buffer_text(v);
  return o.str();
}

EtaEstimator::EtaEstimator(std::vector<double> end_by_line) : end_(std::move(end_by_line)) {
  for (std::size_t i = 1; i < end_.size(); ++i) end_[i] = std::max(end_[i], end_[i - 1]);
}

double EtaEstimator::at_line(long line) const {
  if (end_.empty()) return 0;
  return end_[static_cast<std::size_t>(std::clamp<long>(line, 0, long(end_.size()) - 1))];
}

std::optional<double> EtaEstimator::remaining(long last_answered_line, double elapsed_s) const {
  if (end_.empty()) return std::nullopt;
  const std::size_t k = static_cast<std::size_t>(std::clamp<long>(last_answered_line, 0, long(end_.size()) - 1));
  const double done = end_[k];
  const double left = std::max(0.0, total() - done);
  // Calibrate against reality once a few percent (and a few seconds) of the
  // estimated motion is behind us; before that, trust the planner.
  if (done > 0.03 * total() && elapsed_s > 2.0 && done > 0) return left * (elapsed_s / done);
  return left;
}

}  // namespace cncstream::app
