#include "jog_display.hpp"

#include <cmath>
#include <cstdio>

namespace cncstream::app {

namespace {
std::string dro_axes(const char* name, const std::optional<protocol::Axes>& a) {
  char buf[96];
  if (!a) std::snprintf(buf, sizeof buf, "%s X%8s Y%8s Z%8s", name, "-", "-", "-");
  else std::snprintf(buf, sizeof buf, "%s X%8.3f Y%8.3f Z%8.3f", name, (*a)[0], (*a)[1], (*a)[2]);
  return buf;
}
}  // namespace

std::string format_step(double mm) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", mm);
  return buf;
}

std::string format_dro_line(const DroView& v, int width) {
  std::string s = v.link == "ready" ? (v.state.empty() ? std::string("-") : v.state) : v.link;
  s.append(" | ").append(dro_axes("WPos", v.wpos));
  s.append(" | ").append(dro_axes("MPos", v.mpos));
  char buf[96];
  std::snprintf(buf, sizeof buf, " | step %s mm | feed %.0f mm/min", format_step(v.step_mm).c_str(), v.feed_mm_min);
  s.append(buf);
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
