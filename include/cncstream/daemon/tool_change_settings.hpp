#pragma once
// A machine's tool-change settings in the daemon ([machine.tool_change] in
// the configuration, overridable per job with the same names in the job's
// `tool_change` object): which routine runs at a program's tool change
// (docs/tool-change.md) and where it may move. Turned into the session's
// protocol::ToolChangeConfig when a job starts; a program that changes
// tools without what its method needs is refused, naming the setting.
#include <nlohmann/json.hpp>

#include <array>
#include <optional>
#include <string>

#include "cncstream/protocol/tool_change.hpp"

namespace cncstream::daemon {

struct ToolChangeSettings {
  std::string method = "manual";      // plate | sensor | manual | controller (grblHAL's own) | pause (the M0 goes to the controller)
  std::optional<double> safe_z;       // machine Z (G53) of every XY travel
  std::optional<std::array<double, 2>> plate_at;   // the touch plate's centre, WORK X,Y
  std::optional<std::array<double, 2>> sensor_at;  // the sensor's centre, MACHINE X,Y
  double plate_thickness = 0;         // the probe_z action sets work Z to this at the touch
  double probe_travel = 50;           // mm, the longest probe move down from the safe Z
  double max_length_change = 40;      // a larger difference is questioned
};

// Overrides `s` with the fields `j` has (an object; null fields are left).
// Throws ApiError 400 naming `field_prefix` + the field.
void apply_tool_change_json(ToolChangeSettings& s, const nlohmann::json& j, const std::string& field_prefix);
nlohmann::json tool_change_json(const ToolChangeSettings& s);

// The session's routine for a job; nullopt for `pause`. `changes_tools`: the
// program has a tool change (else missing positions are no reason to refuse).
// Throws std::invalid_argument naming the missing setting.
std::optional<protocol::ToolChangeConfig> routine_config(const ToolChangeSettings& s, bool changes_tools);

}  // namespace cncstream::daemon
