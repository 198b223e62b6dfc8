#pragma once
// The controller's own `$$` settings as the host reads them after
// identification: "$110=500.000" lines -> number -> value, and the motion
// limits the planner needs ($110-$112 max rates, $120-$122 accelerations,
// $11 junction deviation) for a time estimate the controller will match.
#include <map>
#include <optional>
#include <string_view>

#include "cncstream/gcode/motion_planner.hpp"

namespace cncstream::protocol {

using GrblSettings = std::map<int, double>;

// "$n=value" (value a plain number). nullopt for anything else, e.g.
// "$N0=..." startup lines or "[MSG:..]".
std::optional<std::pair<int, double>> parse_setting_line(std::string_view line);

// Motion limits from $110-$112, $120-$122 and $11; nullopt unless all six
// rates and accelerations are present and positive.
std::optional<gcode::MotionLimits> motion_limits_from(const GrblSettings& s);

// GRBL 1.1's shipped defaults (defaults.h: $110-$112 500 mm/min, $120-$122
// 10 mm/s^2, $11 0.010 mm): a real machine's plan before its `$$` is read.
gcode::MotionLimits grbl_default_motion_limits();

}  // namespace cncstream::protocol
