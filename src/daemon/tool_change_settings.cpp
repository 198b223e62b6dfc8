#include "cncstream/daemon/tool_change_settings.hpp"

#include <cmath>
#include <stdexcept>

#include "cncstream/daemon/http_types.hpp"

namespace cncstream::daemon {

using nlohmann::json;

namespace detail_tool_change_settings {

[[noreturn]] void bad(const std::string& field, const std::string& why) {
  throw ApiError{400, "bad_request", cat({field, ": ", why})};
}

double finite(const json& v, const std::string& field, double lo, double hi) {
  if (!v.is_number()) bad(field, cat({"expected a number, got ", v.type_name()}));
  const double x = v.get<double>();
  if (!std::isfinite(x) || x < lo || x > hi)
    bad(field, cat({"must be >= ", num_text(lo), " and <= ", num_text(hi), " (got ", num_text(x), ")"}));
  return x;
}

std::array<double, 2> xy(const json& v, const std::string& field) {
  if (!v.is_array() || v.size() != 2) bad(field, "expected [X, Y] (mm)");
  return {finite(v[0], field, -1e5, 1e5), finite(v[1], field, -1e5, 1e5)};
}

}  // namespace detail_tool_change_settings

void apply_tool_change_json(ToolChangeSettings& s, const json& j, const std::string& prefix) {
  using namespace detail_tool_change_settings;
  if (!j.is_object()) bad(prefix.substr(0, prefix.size() - 1), "expected an object");
  for (const auto& [k, v] : j.items()) {
    const std::string f = prefix + k;
    if (v.is_null()) continue;
    if (k == "method") {
      if (!v.is_string()) bad(f, "expected plate, sensor, manual, controller or pause");
      const auto m = v.get<std::string>();
      if (m != "plate" && m != "sensor" && m != "manual" && m != "controller" && m != "pause")
        bad(f, cat({"'", m.substr(0, 40), "' is not one of plate, sensor, manual, controller, pause"}));
      s.method = m;
    } else if (k == "safe_z") {
      s.safe_z = finite(v, f, -1e4, 1e4);
    } else if (k == "plate_at") {
      s.plate_at = xy(v, f);
    } else if (k == "sensor_at") {
      s.sensor_at = xy(v, f);
    } else if (k == "plate_thickness") {
      s.plate_thickness = finite(v, f, 0, 100);
    } else if (k == "probe_travel") {
      s.probe_travel = finite(v, f, 0.1, 1000);
    } else if (k == "max_length_change") {
      s.max_length_change = finite(v, f, 0.01, 1000);
    } else {
      bad(f, "unknown field (method, safe_z, plate_at, sensor_at, plate_thickness, probe_travel, max_length_change)");
    }
  }
}

json tool_change_json(const ToolChangeSettings& s) {
  const auto pt = [](const std::optional<std::array<double, 2>>& p) {
    return p ? json::array({(*p)[0], (*p)[1]}) : json(nullptr);
  };
  return {{"method", s.method},
          {"safe_z", s.safe_z ? json(*s.safe_z) : json(nullptr)},
          {"plate_at", pt(s.plate_at)},
          {"sensor_at", pt(s.sensor_at)},
          {"plate_thickness", s.plate_thickness},
          {"probe_travel", s.probe_travel},
          {"max_length_change", s.max_length_change}};
}

std::optional<protocol::ToolChangeConfig> routine_config(const ToolChangeSettings& s, bool changes_tools) {
  if (s.method == "pause") return std::nullopt;
  protocol::ToolChangeConfig c;
  c.method = protocol::parse_tool_change_method(s.method);
  c.probe_travel = s.probe_travel;
  c.max_length_change = s.max_length_change;
  if (s.safe_z) c.safe_z = *s.safe_z;
  else if (changes_tools)
    throw std::invalid_argument("the program changes tools and the machine has no tool_change.safe_z (the machine Z, "
                                "G53, for travel with any tool): configure it, or give it in the job's tool_change");
  if (c.method == protocol::ToolChangeMethod::Plate) {
    if (s.plate_at) {
      c.probe_x = (*s.plate_at)[0];
      c.probe_y = (*s.plate_at)[1];
    } else if (changes_tools) {
      throw std::invalid_argument("tool_change.method plate needs tool_change.plate_at [X, Y] (work coordinates)");
    }
  }
  if (c.method == protocol::ToolChangeMethod::Sensor) {
    if (s.sensor_at) {
      c.probe_x = (*s.sensor_at)[0];
      c.probe_y = (*s.sensor_at)[1];
    } else if (changes_tools) {
      throw std::invalid_argument("tool_change.method sensor needs tool_change.sensor_at [X, Y] (machine coordinates)");
    }
  }
  return c;
}

}  // namespace cncstream::daemon
