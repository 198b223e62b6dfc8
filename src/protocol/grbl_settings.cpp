#include "cncstream/protocol/grbl_settings.hpp"

#include <charconv>
#include <cmath>

namespace cncstream::protocol {

std::optional<std::pair<int, double>> parse_setting_line(std::string_view line) {
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.remove_suffix(1);
  if (line.size() < 4 || line[0] != '$') return std::nullopt;
  const auto eq = line.find('=');
  if (eq == std::string_view::npos || eq < 2) return std::nullopt;
  int n = 0;
  const auto key = line.substr(1, eq - 1);
  auto r = std::from_chars(key.data(), key.data() + key.size(), n);
  if (r.ec != std::errc{} || r.ptr != key.data() + key.size() || n < 0) return std::nullopt;
  // Some firmwares append " (description)" after the value.
  auto value = line.substr(eq + 1);
  const auto sp = value.find(' ');
  if (sp != std::string_view::npos) value = value.substr(0, sp);
  double v = 0;
  auto rv = std::from_chars(value.data(), value.data() + value.size(), v);
  if (value.empty() || rv.ec != std::errc{} || rv.ptr != value.data() + value.size() || !std::isfinite(v))
    return std::nullopt;
  return std::make_pair(n, v);
}

std::optional<gcode::MotionLimits> motion_limits_from(const GrblSettings& s) {
  auto get = [&](int n) -> std::optional<double> {
    const auto it = s.find(n);
    if (it == s.end() || !(it->second > 0)) return std::nullopt;
    return it->second;
  };
  const auto rx = get(110), ry = get(111), rz = get(112), ax = get(120), ay = get(121), az = get(122);
  if (!rx || !ry || !rz || !ax || !ay || !az) return std::nullopt;
  gcode::MotionLimits m;
  m.max_rate = {*rx, *ry, *rz};
  m.acceleration = {*ax, *ay, *az};
  if (const auto it = s.find(11); it != s.end() && it->second >= 0) m.junction_deviation = it->second;
  return m;
}

gcode::MotionLimits grbl_default_motion_limits() {
  return *motion_limits_from(GrblSettings{{11, 0.010}, {110, 500}, {111, 500}, {112, 500},
                                          {120, 10},   {121, 10},  {122, 10}});
}

}  // namespace cncstream::protocol
