#include "jog_display.hpp"

#include <fmt/core.h>

#include <cmath>

namespace cncstream::app {

namespace {
std::string dro_axes(const char* name, const std::optional<protocol::Axes>& a) {
  if (!a) return fmt::format("{} X{:>8} Y{:>8} Z{:>8}", name, "-", "-", "-");
  return fmt::format("{} X{:8.3f} Y{:8.3f} Z{:8.3f}", name, (*a)[0], (*a)[1], (*a)[2]);
}
}  // namespace

std::string format_step(double mm) { return fmt::format("{:g}", mm); }

std::string format_dro_line(const DroView& v, int width) {
  std::string s = v.link == "ready" ? (v.state.empty() ? std::string("-") : v.state) : v.link;
  s.append(" | ").append(dro_axes("WPos", v.wpos));
  s.append(" | ").append(dro_axes("MPos", v.mpos));
  s.append(fmt::format(" | step {} mm | feed {:.0f} mm/min", format_step(v.step_mm), v.feed_mm_min));
  if (!v.jog.empty()) s.append(" | ").append(v.jog);
  if (!v.message.empty()) s.append(" | ").append(v.message);
  if (width > 3 && static_cast<int>(s.size()) > width) s = s.substr(0, static_cast<std::size_t>(width - 3)) + "...";
  return s;
}

const char* jog_keys_help() {
  return "keys: arrows X/Y, PgUp/PgDn Z (tap: one step, hold: continuous) | 1-4 step 0.01/0.1/1/10 mm | "
         "+/- jog feed | 0 zero XYZ, X/Y/Z zero one axis | h home | u unlock | p probe Z | g go to work zero | "
         "s safe Z | space or ! cancel jogs / feed hold | ~ resume | Ctrl-X reset | Esc stop jog | ? keys | q quit";
}

}  // namespace cncstream::app
