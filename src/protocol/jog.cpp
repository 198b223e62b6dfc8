#include "cncstream/protocol/jog.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace cncstream::protocol {

namespace {

}  // namespace

std::string relative_move_words(const JogDirection& dir, double length, double feed) {
  const double n = std::sqrt(dir.v[0] * dir.v[0] + dir.v[1] * dir.v[1] + dir.v[2] * dir.v[2]);
  if (!(n > 0) || !std::isfinite(n)) throw std::invalid_argument("jog: direction must be a non-zero vector");
  if (!(feed > 0) || !std::isfinite(feed)) throw std::invalid_argument("jog: feed must be positive");
  if (!(length > 0) || !std::isfinite(length)) throw std::invalid_argument("jog: distance must be positive");
  std::string out;
  static constexpr char kAxis[3] = {'X', 'Y', 'Z'};
  char buf[48];
  for (int i = 0; i < 3; ++i) {
    const double d = dir.v[i] / n * length;
    if (std::fabs(d) < 0.0005) continue;  // below the controller's 0.001 mm resolution
    std::snprintf(buf, sizeof buf, "%c%.3f", kAxis[i], d);
    out += buf;
  }
  std::snprintf(buf, sizeof buf, "F%.0f", feed);
  out += buf;
  return out;
}

namespace {

std::string format_jog(const JogDirection& dir, double length, double feed) {
  return "$J=G91G21" + relative_move_words(dir, length, feed);
}

}  // namespace

std::string jog_segment_line(const JogDirection& dir, double feed_mm_min, double segment_s) {
  if (!(segment_s > 0)) throw std::invalid_argument("jog: segment time must be positive");
  return format_jog(dir, feed_mm_min / 60.0 * segment_s, feed_mm_min);
}

std::string jog_step_line(const JogDirection& dir, double distance_mm, double feed_mm_min) {
  return format_jog(dir, distance_mm, feed_mm_min);
}

}  // namespace cncstream::protocol
