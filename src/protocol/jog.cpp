#include "cncstream/protocol/jog.hpp"

#include <fmt/core.h>

#include <cmath>

namespace cncstream::protocol {

std::string move_words(const std::array<double, 3>& delta, double feed) {
  static constexpr char kAxis[3] = {'X', 'Y', 'Z'};
  std::string out;
  for (int i = 0; i < 3; ++i) {
    if (std::fabs(delta[i]) < 0.0005) continue;
    out += fmt::format("{}{:.3f}", kAxis[i], delta[i]);
  }
  out += fmt::format("F{:.0f}", feed);
  return out;
}

std::string grbl_jog_line(const std::array<double, 3>& delta, double feed) {
  std::string s = "$J=G91G21";
  s += move_words(delta, feed);
  return s;
}

}  // namespace cncstream::protocol
