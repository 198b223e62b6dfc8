#include "cncstream/protocol/machine_actions.hpp"

#include <fmt/core.h>

#include <cmath>
#include <cstdlib>
#include <stdexcept>

namespace cncstream::protocol {

std::vector<std::string> zero_axes_lines(std::string_view axes, ActionFamily f) {
  if (axes.empty()) throw std::invalid_argument("zero: name the axes to zero (X, Y, Z)");
  std::string words;
  for (char c : axes) {
    const char u = static_cast<char>(c >= 'a' && c <= 'z' ? c - 'a' + 'A' : c);
    if (u != 'X' && u != 'Y' && u != 'Z')
      throw std::invalid_argument(std::string("zero: '") + c + "' is not an axis (X, Y or Z)");
    if (words.find(u) != std::string::npos) continue;
    words += u;
    words += '0';
  }
  return {(f == ActionFamily::Grbl ? "G10L20P0" : "G92") + words};
}

std::vector<std::string> safe_z_lines(const MachineActionSettings& s, std::optional<double> work_z) {
  if (s.safe_z_machine_mm) return {fmt::format("G21G53G0Z{:.3f}", *s.safe_z_machine_mm)};
  if (work_z && *work_z >= s.safe_z_mm) return {};  // already above: never down
  return {fmt::format("G21G90G0Z{:.3f}", s.safe_z_mm)};
}

std::vector<std::string> go_to_work_zero_lines(const MachineActionSettings& s, std::optional<double> work_z) {
  auto lines = safe_z_lines(s, work_z);
  lines.emplace_back("G21G90G0X0Y0");
  lines.emplace_back("G0Z0");
  return lines;
}

std::vector<std::string> spindle_lines(bool on, const MachineActionSettings& s) {
  if (!on) return {"M5"};
  if (!(s.spindle_rpm > 0)) throw std::invalid_argument("spindle: the speed must be positive");
  return {fmt::format("M3S{:.0f}", s.spindle_rpm)};
}

std::vector<std::string> probe_z_lines(const MachineActionSettings& s) {
  if (!(s.probe_travel_mm > 0) || !(s.probe_feed_mm_min > 0))
    throw std::invalid_argument("probe: travel and feed must be positive");
  // Relative search, then absolute again whatever the answer.
  return {fmt::format("G21G91G38.2Z{:.3f}F{:.0f}", -s.probe_travel_mm, s.probe_feed_mm_min), "G90"};
}

std::optional<ProbeReport> parse_probe_report(std::string_view line) {
  constexpr std::string_view head = "[PRB:";
  if (line.substr(0, head.size()) != head || line.empty() || line.back() != ']') return std::nullopt;
  const std::string body(line.substr(head.size(), line.size() - head.size() - 1));
  ProbeReport r;
  double* out[3] = {&r.x, &r.y, &r.z};
  const char* p = body.c_str();
  for (int i = 0; i < 3; ++i) {
    char* end = nullptr;
    *out[i] = std::strtod(p, &end);
    if (end == p || !std::isfinite(*out[i])) return std::nullopt;
    p = end;
    if (i < 2) {
      if (*p != ',') return std::nullopt;
      ++p;
    }
  }
  // Extra axes (A, B...) may follow before the ':'.
  while (*p == ',') {
    char* end = nullptr;
    (void)std::strtod(p + 1, &end);
    if (end == p + 1) return std::nullopt;
    p = end;
  }
  if (p[0] != ':' || (p[1] != '0' && p[1] != '1') || p[2] != '\0') return std::nullopt;
  r.touched = p[1] == '1';
  return r;
}

std::vector<std::string> probe_finish_lines(const MachineActionSettings& s, double touch_mz) {
  // The machine stops a little past the touch: go back to it before setting Z.
  return {fmt::format("G21G53G1Z{:.3f}F{:.0f}", touch_mz, s.probe_feed_mm_min),
          fmt::format("G10L20P0Z{:.3f}", s.probe_plate_mm), fmt::format("G21G91G0Z{:.3f}", s.probe_retract_mm), "G90"};
}

}  // namespace cncstream::protocol
