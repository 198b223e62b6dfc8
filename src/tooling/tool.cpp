#include "cncstream/tooling/tool.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <stdexcept>

#include "cncstream/cam/cutter.hpp"
#include "lower_case.hpp"

namespace cncstream::tooling {

namespace detail_tool {

std::string num(double v) { return fmt::format("{:.10g}", v); }

std::vector<std::string_view> split_colons(std::string_view s) {
  std::vector<std::string_view> parts;
  std::size_t start = 0;
  for (;;) {
    const auto colon = s.find(':', start);
    parts.push_back(s.substr(start, colon == std::string_view::npos ? s.npos : colon - start));
    if (colon == std::string_view::npos) break;
    start = colon + 1;
  }
  return parts;
}

// A length in the cutter spec's syntax (6, 3.175, 1/8in, 6mm): the cam's own
// parser reads it as a flat's diameter, so the two syntaxes cannot drift.
double length(std::string_view spec, std::string_view part, const char* what) {
  if (part == "0") return 0;
  try {
    return cam::parse_cutter_spec(fmt::format("flat:{}", part)).diameter();
  } catch (const std::exception&) {
    throw std::invalid_argument(fmt::format("bad tool spec '{}': {} '{}' is not a positive length (mm, or 1/8in)",
                                            spec, what, part));
  }
}

double degrees(std::string_view spec, std::string_view part, const char* what) {
  std::string_view t = part;
  if (t.size() > 3 && t.substr(t.size() - 3) == "deg") t.remove_suffix(3);
  double v = 0;
  const auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (t.empty() || ec != std::errc() || p != t.data() + t.size() || !std::isfinite(v))
    throw std::invalid_argument(fmt::format("bad tool spec '{}': {} '{}' is not a number of degrees", spec, what, part));
  return v;
}

}  // namespace detail_tool

const char* shape_name(ToolShape s) {
  switch (s) {
    case ToolShape::Flat: return "flat";
    case ToolShape::Ball: return "ball";
    case ToolShape::Bull: return "bull";
    case ToolShape::VBit: return "vbit";
    case ToolShape::TaperedBall: return "taper";
  }
  return "?";
}

std::optional<ToolShape> shape_from_name(std::string_view name) {
  for (ToolShape s : {ToolShape::Flat, ToolShape::Ball, ToolShape::Bull, ToolShape::VBit, ToolShape::TaperedBall})
    if (name == shape_name(s)) return s;
  return std::nullopt;
}

std::string ToolGeometry::spec() const {
  using detail_tool::num;
  switch (shape) {
    case ToolShape::Flat: return fmt::format("flat:{}", num(diameter));
    case ToolShape::Ball: return fmt::format("ball:{}", num(diameter));
    case ToolShape::Bull: return fmt::format("bull:{}:{}", num(diameter), num(corner_radius));
    case ToolShape::VBit:
      return tip_diameter > 0 ? fmt::format("vbit:{}:{}:{}", num(angle), num(diameter), num(tip_diameter))
                              : fmt::format("vbit:{}:{}", num(angle), num(diameter));
    case ToolShape::TaperedBall:
      return diameter > 0 ? fmt::format("taper:{}:{}:{}", num(tip_diameter), num(angle), num(diameter))
                          : fmt::format("taper:{}:{}", num(tip_diameter), num(angle));
  }
  return {};
}

std::string ToolGeometry::description() const {
  using detail_tool::num;
  switch (shape) {
    case ToolShape::Flat: return fmt::format("{} mm flat end mill", num(diameter));
    case ToolShape::Ball: return fmt::format("{} mm ball-nose end mill", num(diameter));
    case ToolShape::Bull:
      return fmt::format("{} mm bull-nose end mill, {} mm corner radius", num(diameter), num(corner_radius));
    case ToolShape::VBit:
      return tip_diameter > 0 ? fmt::format("{}° V-bit, {} mm, {} mm flat tip", num(angle), num(diameter), num(tip_diameter))
                              : fmt::format("{}° V-bit, {} mm", num(angle), num(diameter));
    case ToolShape::TaperedBall:
      return diameter > 0 ? fmt::format("{} mm tapered ball-nose, {}° per side, {} mm at the top", num(tip_diameter),
                                        num(angle), num(diameter))
                          : fmt::format("{} mm tapered ball-nose, {}° per side", num(tip_diameter), num(angle));
  }
  return {};
}

double ToolGeometry::cutting_diameter() const {
  if (shape == ToolShape::TaperedBall && !(diameter > 0)) return tip_diameter;
  return diameter;
}

ToolGeometry parse_tool_spec(std::string_view spec) {
  using namespace detail_tool;
  const auto parts = split_colons(spec);
  const std::string_view kind = parts[0];
  ToolGeometry g;
  if (kind == "flat" || kind == "ball" || kind == "bull") {
    cam::Cutter c;
    try {
      c = cam::parse_cutter_spec(spec);
    } catch (const cam::CutterSpecError& e) {
      throw std::invalid_argument(e.what());
    }
    g.shape = c.type == cam::CutterType::Flat ? ToolShape::Flat : c.type == cam::CutterType::Ball ? ToolShape::Ball : ToolShape::Bull;
    g.diameter = c.diameter();
    g.corner_radius = c.type == cam::CutterType::Flat ? 0.0 : c.corner_radius;
    return g;
  }
  const std::string usage =
      " (expected flat:D, ball:D, bull:D:r, vbit:ANGLE:D[:TIP_W] or taper:TIP_D:ANGLE_PER_SIDE[:TOP_D])";
  if (kind == "vbit") {
    if (parts.size() != 3 && parts.size() != 4)
      throw std::invalid_argument(fmt::format("bad tool spec '{}': 'vbit' takes the included angle, the diameter and "
                                              "optionally the flat tip's width{}",
                                              spec, usage));
    g.shape = ToolShape::VBit;
    g.angle = degrees(spec, parts[1], "included angle");
    g.diameter = length(spec, parts[2], "diameter");
    if (parts.size() == 4) g.tip_diameter = length(spec, parts[3], "tip width");
  } else if (kind == "taper") {
    if (parts.size() != 3 && parts.size() != 4)
      throw std::invalid_argument(fmt::format("bad tool spec '{}': 'taper' takes the tip diameter, the angle per side "
                                              "and optionally the diameter at the top of the flutes{}",
                                              spec, usage));
    g.shape = ToolShape::TaperedBall;
    g.tip_diameter = length(spec, parts[1], "tip diameter");
    g.angle = degrees(spec, parts[2], "angle per side");
    if (parts.size() == 4) g.diameter = length(spec, parts[3], "top diameter");
  } else {
    throw std::invalid_argument(fmt::format("bad tool spec '{}': unknown tool type '{}'{}", spec, kind, usage));
  }
  Tool t;
  t.name = "spec";
  t.number = 1;
  t.geometry = g;
  try {
    check_tool(t);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(fmt::format("bad tool spec '{}': {}", spec, e.what()));
  }
  return g;
}

const CuttingData* Tool::cutting_for(std::string_view material) const {
  using detail_lower_case::lower;
  const std::string m = lower(material);
  for (const auto& c : cutting)
    if (lower(c.material) == m) return &c;
  return nullptr;
}

void check_tool(const Tool& t) {
  using detail_tool::num;
  const ToolGeometry& g = t.geometry;
  auto fail = [&](const std::string& why) {
    throw std::invalid_argument(t.name.empty() ? why : fmt::format("tool {} '{}': {}", t.number, t.name, why));
  };
  if (t.number < 1 || t.number > 9999) fail(fmt::format("number {} is out of range 1..9999", t.number));
  if (t.name.empty()) fail("no name");
  if (t.name.size() > 80) fail("the name is longer than 80 characters");
  if (t.flutes < 1 || t.flutes > 12) fail(fmt::format("{} flutes: expected 1 to 12", t.flutes));
  for (double v : {t.flute_length, t.overall_length, t.stick_out, t.shank_diameter})
    if (!(v >= 0 && v < 1000)) fail("lengths must be >= 0 and < 1000 mm, got " + num(v));
  auto positive = [&](double v, const char* what) {
    if (!(v > 0 && v <= 200)) fail(fmt::format("{} {} mm: expected > 0 and <= 200", what, num(v)));
  };
  switch (g.shape) {
    case ToolShape::Flat:
    case ToolShape::Ball: positive(g.diameter, "diameter"); break;
    case ToolShape::Bull:
      positive(g.diameter, "diameter");
      if (!(g.corner_radius > 0 && g.corner_radius < g.diameter / 2))
        fail(fmt::format("corner radius {} mm: expected between 0 and the radius {} mm", num(g.corner_radius),
                         num(g.diameter / 2)));
      break;
    case ToolShape::VBit:
      positive(g.diameter, "diameter");
      if (!(g.angle > 0 && g.angle < 180)) fail(fmt::format("included angle {}°: expected between 0 and 180", num(g.angle)));
      if (!(g.tip_diameter >= 0 && g.tip_diameter < g.diameter))
        fail(fmt::format("tip width {} mm: expected >= 0 and below the diameter {} mm", num(g.tip_diameter),
                         num(g.diameter)));
      break;
    case ToolShape::TaperedBall:
      positive(g.tip_diameter, "tip diameter");
      if (!(g.angle > 0 && g.angle < 45))
        fail(fmt::format("angle per side {}°: expected between 0 and 45 (the included angle is twice it)", num(g.angle)));
      if (!(g.diameter == 0 || (g.diameter > g.tip_diameter && g.diameter <= 200)))
        fail(fmt::format("top diameter {} mm: expected above the tip diameter {} mm", num(g.diameter),
                         num(g.tip_diameter)));
      break;
  }
  for (const auto& c : t.cutting) {
    if (c.material.empty()) fail("cutting data without a material");
    for_each_value(c, [&](const char* key, const std::optional<double>& v) {
      if (v && !(*v > 0 && *v < 1e6)) fail(fmt::format("cutting data for {}: {} must be positive", c.material, key));
    });
  }
}

}  // namespace cncstream::tooling
