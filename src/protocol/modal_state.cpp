#include "cncstream/protocol/modal_state.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>

namespace cncstream::protocol {

namespace {

std::string g_name(double v) {
  char buf[16];
  if (std::fabs(v - std::round(v)) < 1e-6) std::snprintf(buf, sizeof buf, "G%d", static_cast<int>(std::lround(v)));
  else std::snprintf(buf, sizeof buf, "G%.1f", v);
  return buf;
}

}  // namespace

void ModalState::apply(std::string_view s) {
  if (s.empty() || s.front() == '$') return;  // system commands carry no modal words
  std::size_t i = 0;
  while (i < s.size()) {
    const char l = static_cast<char>(std::toupper(static_cast<unsigned char>(s[i])));
    ++i;
    if (l < 'A' || l > 'Z') continue;
    std::size_t j = i;
    while (j < s.size() && (std::isdigit(static_cast<unsigned char>(s[j])) || s[j] == '.' || s[j] == '-' || s[j] == '+'))
      ++j;
    auto num = s.substr(i, j - i);
    i = j;
    if (!num.empty() && num.front() == '+') num.remove_prefix(1);
    double v = 0;
    if (num.empty() || std::from_chars(num.data(), num.data() + num.size(), v).ec != std::errc{}) continue;
    const int iv = static_cast<int>(std::lround(v));
    const bool integral = std::fabs(v - iv) < 1e-6;
    switch (l) {
      case 'G':
        if (integral && (iv == 20 || iv == 21)) units = g_name(v);
        else if (integral && (iv == 90 || iv == 91)) distance = g_name(v);
        else if (integral && (iv >= 17 && iv <= 19)) plane = g_name(v);
        else if (integral && iv >= 54 && iv <= 59) wcs = g_name(v);
        else if (!integral && iv >= 59 && v < 59.95) wcs = g_name(v);
        else if (integral && iv >= 0 && iv <= 3) motion = g_name(v);
        else if (!integral && std::fabs(v - 38.2) < 0.3) motion = g_name(v);
        else if (integral && iv == 80) motion = "G80";
        break;
      case 'M':
        if (iv == 3) spindle = "M3";
        else if (iv == 4) spindle = "M4";
        else if (iv == 5) spindle = "M5";
        else if (iv == 7) mist = true;
        else if (iv == 8) flood = true;
        else if (iv == 9) mist = flood = false;
        else if (iv == 2 || iv == 30) {  // program end resets these per GRBL
          distance = "G90";
          plane = "G17";
          wcs = "G54";
          motion = "G1";
          spindle = "M5";
          mist = flood = false;
        }
        break;
      case 'F': feed = v; break;
      case 'S': spindle_speed = v; break;
      case 'T': tool = iv; break;
      default: break;
    }
  }
}

std::string ModalState::coolant() const {
  if (mist && flood) return "M7M8";
  if (mist) return "M7";
  if (flood) return "M8";
  return "M9";
}

std::string ModalState::preamble() const {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%s %s %s %s F%.4g S%.6g T%d", units.c_str(), distance.c_str(), plane.c_str(),
                wcs.c_str(), feed, spindle_speed, tool);
  return std::string(buf) + "\n" + spindle + "\n" + (coolant() == "M7M8" ? "M7\nM8" : coolant()) + "\n";
}

std::string ModalState::to_json() const {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "{\"units\":\"%s\",\"distance\":\"%s\",\"plane\":\"%s\",\"wcs\":\"%s\",\"motion\":\"%s\","
                "\"feed\":%.6g,\"spindle_speed\":%.6g,\"spindle\":\"%s\",\"coolant\":\"%s\",\"tool\":%d",
                units.c_str(), distance.c_str(), plane.c_str(), wcs.c_str(), motion.c_str(), feed, spindle_speed,
                spindle.c_str(), coolant().c_str(), tool);
  std::string out = buf;
  if (wco) {
    std::snprintf(buf, sizeof buf, ",\"wco\":[%.4f,%.4f,%.4f]", (*wco)[0], (*wco)[1], (*wco)[2]);
    out += buf;
  }
  return out + "}";
}

}  // namespace cncstream::protocol
