// Fusion 360 tool library (JSON): {"data": [tool, ...]}; per tool `type`,
// `unit`, `description`, `geometry` {DC, NOF, LCF, OAL, SFDM, RE, TA,
// tip-diameter}, `post-process` {number}, `start-values` {presets: [{name,
// n, v_c, f_z, v_f, v_f_plunge, stepdown, stepover}]}. TA is the angle per
// side (a 90° chamfer mill has TA 45). Lengths and feeds are in the tool's
// unit ("inches": in and in/min, v_c in ft/min).
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "cncstream/tooling/tool_import.hpp"
#include "import_common.hpp"
#include "import_json.hpp"

namespace cncstream::tooling {

namespace detail_fusion {

using nlohmann::json;
using detail_import_json::JsonPlace;

}  // namespace detail_fusion

ImportResult import_fusion_library(std::string_view text, const std::string& source) {
  using namespace detail_fusion;
  ImportResult r;
  r.format = "Fusion 360 tool library";
  const json root = detail_import_json::parse_json(text, source);
  const JsonPlace top{source, ""};
  // Older exports: a bare array of tools.
  const json* data = root.is_array() ? &root : nullptr;
  if (!data) {
    if (!root.is_object() || !root.contains("data")) top.fail("expected an object with \"data\": [tools]");
    data = &root.at("data");
    if (!data->is_array()) top.at("data").fail("expected an array of tools");
  }
  const JsonPlace list = root.is_array() ? top : top.at("data");
  for (std::size_t k = 0; k < data->size(); ++k) {
    const json& j = (*data)[k];
    const JsonPlace p = list.at(k);
    if (!j.is_object()) p.fail("expected a tool object");
    const std::string type = p.str(j, "type").value_or("");
    const std::string unit = p.str(j, "unit").value_or("millimeters");
    double scale = 1;
    if (unit == "inches") scale = 25.4;
    else if (unit != "millimeters") p.at("unit").fail(fmt::format("unknown unit '{}'", unit));
    std::string name = p.str(j, "description").value_or("");
    const std::string entry = fmt::format("{} '{}' ({})", p.pointer, name, type);
    if (!j.contains("geometry") || !j.at("geometry").is_object()) {
      r.skipped.push_back(entry + ": no geometry");
      continue;
    }
    const json& g = j.at("geometry");
    const JsonPlace gp = p.at("geometry");
    auto len = [&](const char* key) { return gp.num(g, key).value_or(0) * scale; };
    Tool t;
    const double dc = len("DC"), re = len("RE"), ta = gp.num(g, "TA").value_or(0);
    const double tip = len("tip-diameter");
    ToolGeometry& geo = t.geometry;
    if (type == "flat end mill") {
      geo.shape = ToolShape::Flat;
      geo.diameter = dc;
    } else if (type == "ball end mill") {
      geo.shape = ToolShape::Ball;
      geo.diameter = dc;
    } else if (type == "bull nose end mill") {
      geo.shape = ToolShape::Bull;
      geo.diameter = dc;
      geo.corner_radius = re;
      if (re <= 0) geo.shape = ToolShape::Flat;
      else if (re >= dc / 2) geo.shape = ToolShape::Ball;
    } else if (type == "chamfer mill" || type == "engrave mill" || type == "spot drill") {
      geo.shape = ToolShape::VBit;
      geo.diameter = dc;
      geo.angle = 2 * ta;
      geo.tip_diameter = tip;
      if (!(ta > 0)) {
        r.skipped.push_back(entry + ": no taper angle (TA)");
        continue;
      }
    } else if (type == "tapered mill") {
      if (!(re > 0)) {
        r.skipped.push_back(entry + ": a tapered flat end mill (RE 0) has no shape here; tapered ball-noses only");
        continue;
      }
      geo.shape = ToolShape::TaperedBall;
      geo.tip_diameter = 2 * re;
      geo.angle = ta;
      // The top of the flutes, from the flute length (the cone tangent to the ball).
      const double lcf = len("LCF"), rr = re, a = ta * std::numbers::pi / 180;
      if (lcf > rr * (1 - std::sin(a)))
        geo.diameter = 2 * (rr * std::cos(a) + (lcf - rr * (1 - std::sin(a))) * std::tan(a));
    } else {
      r.skipped.push_back(fmt::format("{}: type '{}' has no shape here (flat, ball, bull nose, chamfer and tapered "
                                      "mills are imported)",
                                      entry, type));
      continue;
    }
    if (const auto f = gp.num(g, "NOF")) t.flutes = static_cast<int>(std::lround(*f));
    t.flute_length = len("LCF");
    t.overall_length = len("OAL");
    t.shank_diameter = len("SFDM");
    if (j.contains("post-process") && j.at("post-process").is_object())
      t.number = static_cast<int>(p.at("post-process").num(j.at("post-process"), "number").value_or(0));
    t.name = name.empty() ? geo.description() : name;
    if (t.number < 0 || t.number > 9999) t.number = 0;
    // Presets: cutting data per material (the preset's name).
    std::vector<std::string> presets;
    if (j.contains("start-values") && j.at("start-values").is_object()) {
      const json& sv = j.at("start-values");
      const JsonPlace sp = p.at("start-values");
      if (sv.contains("presets")) {
        if (!sv.at("presets").is_array()) sp.at("presets").fail("expected an array of presets");
        for (std::size_t i = 0; i < sv.at("presets").size(); ++i) {
          const json& pr = sv.at("presets")[i];
          const JsonPlace pp = sp.at("presets").at(i);
          if (!pr.is_object()) pp.fail("expected a preset object");
          CuttingData c;
          c.material = pp.str(pr, "name").value_or("");
          if (c.material.empty()) continue;
          auto pos = [](std::optional<double> v, double s) -> std::optional<double> {
            if (v && *v > 0) return *v * s;
            return std::nullopt;
          };
          c.rpm = pos(pp.num(pr, "n"), 1);
          c.surface_speed = pos(pp.num(pr, "v_c"), scale == 1 ? 1 : 0.3048);
          c.chip_load = pos(pp.num(pr, "f_z"), scale);
          c.feed = pos(pp.num(pr, "v_f"), scale);
          c.plunge_feed = pos(pp.num(pr, "v_f_plunge"), scale);
          c.stepdown = pos(pp.num(pr, "stepdown"), scale);
          c.stepover = pos(pp.num(pr, "stepover"), scale);
          if (t.cutting_for(c.material)) continue;  // the first of a name
          presets.push_back(c.material);
          t.cutting.push_back(c);
        }
      }
    }
    detail_import_common::accept_tool(
        r, std::move(t), entry, presets.empty() ? std::string() : fmt::format(", presets: {}", fmt::join(presets, ", ")));
  }
  return r;
}

}  // namespace cncstream::tooling
