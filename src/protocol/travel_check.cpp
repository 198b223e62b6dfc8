#include "cncstream/protocol/travel_check.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>

namespace cncstream::protocol {

namespace {

constexpr double kSlackMm = 0.001;  // rounding in the program's numbers

std::string mm(double v) { return fmt::format("{:.6g}", v); }

}  // namespace

std::optional<std::array<double, 3>> max_travel_from(const GrblSettings& settings) {
  // Homing off: GRBL uses $130-$132 for nothing, and a machine that never set
  // them reports the default 200 mm whatever its size.
  const auto homing = settings.find(22);
  if (homing == settings.end() || homing->second == 0) return std::nullopt;
  std::array<double, 3> t{};
  for (int i = 0; i < 3; ++i) {
    const auto it = settings.find(130 + i);
    if (it == settings.end() || !std::isfinite(it->second) || !(it->second > 0)) return std::nullopt;
    t[static_cast<std::size_t>(i)] = it->second;
  }
  return t;
}

std::optional<std::string> travel_refusal(const gcode::ProgramExtent& extent, const std::array<double, 3>& travel_mm) {
  static const char axis_name[3] = {'X', 'Y', 'Z'};
  std::string text;
  bool fits_at_inch = true, fits_at_thousandth = true;
  double ratio = 0;  // the largest of extent / travel
  for (std::size_t i = 0; i < 3; ++i) {
    const gcode::AxisExtent& a = extent.axes[i];
    const double size = a.size(), travel = travel_mm[i];
    if (!(size > travel + kSlackMm)) continue;
    if (text.empty()) text = "the program does not fit the machine's travel:";
    text.append("\n  ").push_back(axis_name[i]);
    text.append(": the program spans ").append(mm(size)).append(" mm (").append(mm(a.lo)).append(" .. ");
    text.append(mm(a.hi)).append(" as traced), the machine travels ").append(mm(travel)).append(" mm ($");
    text.append(std::to_string(130 + i)).append(")");
    ratio = std::max(ratio, size / travel);
    fits_at_inch = fits_at_inch && size / 25.4 <= travel + kSlackMm;
    fits_at_thousandth = fits_at_thousandth && size / 1000 <= travel + kSlackMm;
  }
  if (text.empty()) return std::nullopt;
  text.append("\n  nothing was sent. ");
  // Less than twice the travel is a part too large, not a unit factor.
  if (ratio < 2)
    text.append("The part is larger than the machine can move (check the part, --scale and --bounds).");
  else if (fits_at_inch)
    text.append("Likely cause: units, 25.4 times too large: a part drawn in mm taken for inches (--units in), or a "
                "program in mm marked G20 (inches).");
  else if (fits_at_thousandth)
    text.append("Likely cause: units, 1000 times too large: a part drawn in mm taken for metres (--units m), or "
                "drawn in micrometres.");
  else
    text.append("The part is far larger than the machine (check --units and --scale).");
  text.append(" If the machine's travel is larger, set $130-$132 to it.");
  return text;
}

}  // namespace cncstream::protocol
