#include "cncstream/daemon/job_params.hpp"

#include <fmt/core.h>

#include <cmath>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/daemon/http_types.hpp"
#include "cncstream/jobs/operation_feeds.hpp"

namespace cncstream::daemon {

using nlohmann::json;

namespace {

[[noreturn]] void bad(const std::string& field, const std::string& why) {
  throw ApiError{400, "bad_request", "params." + field + ": " + why};
}

double number(const json& j, const char* key, double dflt, double lo, double hi, bool lo_open = false) {
  if (!j.contains(key) || j.at(key).is_null()) return dflt;
  const auto& v = j.at(key);
  if (!v.is_number()) bad(key, cat({"expected a number, got ", v.type_name()}));
  const double x = v.get<double>();
  if (!std::isfinite(x) || (lo_open ? !(x > lo) : !(x >= lo)) || !(x <= hi))
    bad(key, cat({"must be ", lo_open ? "> " : ">= ", num_text(lo), " and <= ", num_text(hi), " (got ", num_text(x), ")"}));
  return x;
}

std::optional<double> opt_number(const json& j, const char* key, double lo, double hi) {
  if (!j.contains(key) || j.at(key).is_null()) return std::nullopt;
  return number(j, key, 0, lo, hi);
}

std::string choice(const json& j, const char* key, const std::string& dflt, std::initializer_list<const char*> allowed) {
  if (!j.contains(key) || j.at(key).is_null()) return dflt;
  const auto& v = j.at(key);
  if (!v.is_string()) bad(key, "expected a string");
  std::string s = v.get<std::string>();
  std::string list;
  for (const char* a : allowed) {
    if (s == a) return s;
    list += list.empty() ? "" : ", ";
    list += a;
  }
  bad(key, cat({"'", s.substr(0, 40), "' is not one of ", list}));
}

}  // namespace

CheckedParams check_toolpath_params(const json& j, const FileInfo& file, const Limits& limits,
                                    const tooling::ToolLibrary* tools, const tooling::MachineLimits& machine) {
  if (!j.is_object()) throw ApiError{400, "bad_request", "params: expected an object"};
  CheckedParams out;
  auto& p = out.params;
  const tooling::ToolLibrary no_tools;
  // A spec, or a tool of the library by number or name: its spec and the tool.
  auto choose = [&](const char* field, const std::string& text) {
    try {
      return tooling::choose_tool(tools ? *tools : no_tools, text);
    } catch (const std::exception& e) {
      bad(field, e.what());
    }
  };
  if (!j.contains("tool") || !j.at("tool").is_string())
    bad("tool", "required: a cutter such as ball:3.175, or a tool of the library by number or name");
  if (j.at("tool").get<std::string>().size() > 64) bad("tool", "too long");
  const tooling::ToolChoice tool_choice = choose("tool", j.at("tool").get<std::string>());
  const std::string tool = tool_choice.spec();
  try {
    p.cutter = cam::parse_cutter_spec(tool);
  } catch (const std::exception& e) {
    bad("tool", e.what());
  }
  if (!(p.cutter.diameter() > 0 && p.cutter.diameter() <= 50)) bad("tool", "the diameter must be > 0 and <= 50 mm");
  p.stepover = number(j, "stepover", 0.4, 0.01, 50);
  p.step = number(j, "step", 0, 0, 10);
  if (p.step != 0 && p.step < 0.005) bad("step", "must be 0 (automatic) or >= 0.005 mm");
  const std::string dir = choice(j, "direction", "x", {"x", "y"});
  p.direction = dir == "y" ? cam::RasterDirection::Y : cam::RasterDirection::X;
  const std::string strategy = choice(j, "strategy", "steep-shallow", {"steep-shallow", "raster"});
  p.strategy = strategy == "raster" ? jobs::FinishStrategy::Raster : jobs::FinishStrategy::SteepShallow;
  p.steep_angle = number(j, "steep_angle", 45, 1, 89);
  p.scallop = opt_number(j, "scallop", 0.001, 10);
  p.feed = number(j, "feed", 1000, 0, 100000, true);
  p.plunge_feed = number(j, "plunge_feed", 300, 0, 100000, true);
  p.rpm = number(j, "rpm", 18000, 0, 100000);
  p.safe_z = opt_number(j, "safe_z", -1000, 1000);
  p.tolerance = number(j, "tolerance", jobs::kDefaultTolerance, 0, 1);
  const std::string arcs = choice(j, "arcs", "on", {"on", "off"});
  p.arcs = arcs == "on";
  p.controller_arc_tolerance = number(j, "controller_arc_tolerance", 0.002, 0, 0.1);
  p.floor = opt_number(j, "floor", -10000, 10000);
  const std::string origin = choice(j, "origin", "min", {"min", "center", "model"});
  p.origin = origin == "center" ? XYOrigin::PartCenter : origin == "model" ? XYOrigin::Model : XYOrigin::PartMin;
  const std::string zz = choice(j, "z_zero", "top", {"top", "bottom", "model"});
  p.z_zero = zz == "bottom" ? ZZero::PartBottom : zz == "model" ? ZZero::Model : ZZero::PartTop;
  const std::string units = choice(j, "units", "mm", {"mm", "in"});
  p.part.units = units == "in" ? geometry::LengthUnit::Inch : geometry::LengthUnit::Millimetre;
  p.part.scale = number(j, "scale", 1, 0, 1000, true);
  json bounds = nullptr;
  if (j.contains("bounds") && !j.at("bounds").is_null()) {
    const auto& b = j.at("bounds");
    if (!b.is_array() || b.size() != 4) bad("bounds", "expected [x0, y0, x1, y1]");
    double v[4];
    for (int i = 0; i < 4; ++i) {
      if (!b[i].is_number() || !std::isfinite(b[i].get<double>()) || std::abs(b[i].get<double>()) > 1e5)
        bad("bounds", "expected 4 numbers within +-100000 mm");
      v[i] = b[i].get<double>();
    }
    if (!(v[0] < v[2] && v[1] < v[3])) bad("bounds", "need x0 < x1 and y0 < y1");
    p.bounds = cam::XYBounds{v[0], v[1], v[2], v[3]};
    bounds = json::array({v[0], v[1], v[2], v[3]});
  }
  // Stock and depth of cut, as the CLI's options (toolpath_params).
  const std::string stock = j.contains("stock") && !j.at("stock").is_null()
                                ? (j.at("stock").is_string() ? j.at("stock").get<std::string>()
                                                             : (bad("stock", "expected a string"), std::string()))
                                : std::string("auto");
  if (stock.size() > 200) bad("stock", "too long");
  if (stock != "none") {
    try {
      p.stock = jobs::parse_stock_spec(stock);
    } catch (const std::exception&) {
      bad("stock", "expected none, auto, auto:MARGIN or a block X0,Y0,Z0:X1,Y1,Z1 (work coordinates)");
    }
    // A height map is a file on the daemon's host: not named over the API.
    if (p.stock->kind == jobs::StockSpec::Kind::HeightMap)
      bad("stock", "expected none, auto, auto:MARGIN or a block X0,Y0,Z0:X1,Y1,Z1 (work coordinates)");
  }
  p.max_depth = opt_number(j, "max_depth", 0.01, 100);
  std::string rough;
  std::optional<tooling::ToolChoice> rough_choice, rest_choice;
  if (j.contains("rough") && !j.at("rough").is_null()) {
    if (!j.at("rough").is_string() || j.at("rough").get<std::string>().size() > 64)
      bad("rough", "expected a cutter such as flat:6");
    rough_choice = choose("rough", j.at("rough").get<std::string>());
    rough = rough_choice->spec();
    try {
      p.rough = cam::parse_cutter_spec(rough);
    } catch (const std::exception& e) {
      bad("rough", e.what());
    }
    if (!(p.rough->diameter() > 0 && p.rough->diameter() <= 50)) bad("rough", "the diameter must be > 0 and <= 50 mm");
  }
  if (j.contains("rest") && !j.at("rest").is_null()) {
    if (!j.at("rest").is_string() || j.at("rest").get<std::string>().size() > 64)
      bad("rest", "expected a cutter such as ball:1");
    rest_choice = choose("rest", j.at("rest").get<std::string>());
    try {
      p.rest = cam::parse_cutter_spec(rest_choice->spec());
    } catch (const std::exception& e) {
      bad("rest", e.what());
    }
    if (!(p.rest->diameter() > 0 && p.rest->diameter() <= 50)) bad("rest", "the diameter must be > 0 and <= 50 mm");
  }
  p.rough_max_depth = opt_number(j, "rough_max_depth", 0.01, 100);
  p.leave = number(j, "leave", 0.3, 0, 10);
  p.step_down = opt_number(j, "step_down", 0.01, 100);
  p.rough_stepover = number(j, "rough_stepover", 0, 0, 50);
  p.rough_feed = opt_number(j, "rough_feed", 0.1, 100000);
  const std::string tool_change = choice(j, "tool_change", "m0", {"m0", "m6"});
  p.tool_change = tool_change == "m6" ? ToolChangeCode::M6 : ToolChangeCode::PauseM0;
  if (!p.stock && (p.rough || p.max_depth || p.step_down))
    bad("stock", "none finishes from the part's top without a depth check: rough, max_depth and step_down need a stock");
  auto opt = [](const std::optional<double>& v) { return v ? json(*v) : json(nullptr); };
  p.rough_rpm = opt_number(j, "rough_rpm", 0, 100000);
  p.rest_feed = opt_number(j, "rest_feed", 0.1, 100000);
  p.rest_rpm = opt_number(j, "rest_rpm", 0, 100000);
  // Feeds and speeds from a material: what the request does not give. The
  // canonical params of an earlier check carry the result and its name.
  std::string material;
  if (j.contains("material_used") && j.at("material_used").is_string() &&
      j.at("material_used").get<std::string>().size() <= 64)
    material = j.at("material_used").get<std::string>();
  if (j.contains("material") && !j.at("material").is_null()) {
    if (!j.at("material").is_string() || j.at("material").get<std::string>().size() > 64)
      bad("material", "expected a material such as walnut, mdf or acrylic");
    material = j.at("material").get<std::string>();
    jobs::FeedsRequest q;
    q.material = material;
    auto op_tool = [](const tooling::ToolChoice& c) {
      return jobs::OperationTool{c.geometry, c.tool ? std::optional<tooling::Tool>(*c.tool) : std::nullopt};
    };
    q.finish = op_tool(tool_choice);
    if (rough_choice) q.rough = op_tool(*rough_choice);
    if (rest_choice) q.rest = op_tool(*rest_choice);
    q.limits = machine;
    if (q.limits.spindle_max <= 0) q.limits.spindle_max = 24000;
    auto given = [&](const char* key) {
      return j.contains(key) && !j.at(key).is_null() ? std::optional<double>(j.at(key).get<double>()) : std::nullopt;
    };
    q.feed = given("feed");
    q.plunge_feed = given("plunge_feed");
    q.rpm = given("rpm");
    q.rough_feed = p.rough_feed;
    try {
      jobs::apply_material_feeds(p, q);
    } catch (const std::invalid_argument& e) {
      bad("material", e.what());
    }
  }

  // The grid the CL engine samples: rows across, samples along.
  const double to_mm = (units == "in" ? 25.4 : 1.0) * p.part.scale;
  double w = 0, h = 0;
  if (p.bounds) {
    w = p.bounds->x1 - p.bounds->x0;
    h = p.bounds->y1 - p.bounds->y0;
  } else {
    w = (file.bbox[3] - file.bbox[0]) * to_mm + 2 * p.cutter.radius;
    h = (file.bbox[4] - file.bbox[1]) * to_mm + 2 * p.cutter.radius;
  }
  const double step = p.step > 0 ? p.step : std::min(p.stepover / 4, 0.1);
  const double along = p.direction == cam::RasterDirection::X ? w : h, across = p.direction == cam::RasterDirection::X ? h : w;
  out.grid_nodes = (along / step + 1) * (across / p.stepover + 1);
  if (!(out.grid_nodes <= limits.max_grid_nodes))
    bad("stepover", cat({"the tool path would sample ", num_text(out.grid_nodes), " points (limit ",
                         num_text(limits.max_grid_nodes), "): use a larger stepover or step, or smaller bounds"}));
  out.canonical = {{"tool", tool},       {"stepover", p.stepover},       {"step", p.step},
                   {"direction", dir},   {"feed", p.feed},               {"plunge_feed", p.plunge_feed},
                   {"rpm", p.rpm},       {"safe_z", p.safe_z ? json(*p.safe_z) : json(nullptr)},
                   {"tolerance", p.tolerance}, {"arcs", arcs},
                   {"controller_arc_tolerance", p.controller_arc_tolerance}, {"bounds", bounds},
                   {"floor", p.floor ? json(*p.floor) : json(nullptr)},
                   {"origin", origin},   {"z_zero", zz},                 {"units", units},
                   {"scale", p.part.scale},
                   {"strategy", strategy}, {"steep_angle", p.steep_angle},
                   {"scallop", p.scallop ? json(*p.scallop) : json(nullptr)},
                   {"stock", stock},     {"max_depth", opt(p.max_depth)},
                   {"rough", rough.empty() ? json(nullptr) : json(rough)},
                   {"rough_max_depth", opt(p.rough_max_depth)}, {"leave", p.leave},
                   {"step_down", opt(p.step_down)}, {"rough_stepover", p.rough_stepover},
                   {"rough_feed", opt(p.rough_feed)}, {"tool_change", tool_change},
                   {"rest", p.rest ? json(p.rest->spec()) : json(nullptr)},
                   {"rough_rpm", opt(p.rough_rpm)}, {"rest_feed", opt(p.rest_feed)}, {"rest_rpm", opt(p.rest_rpm)},
                   // Informational: the feeds above are the material's, computed once.
                   {"material_used", material.empty() ? json(nullptr) : json(material)}};
  return out;
}

}  // namespace cncstream::daemon
