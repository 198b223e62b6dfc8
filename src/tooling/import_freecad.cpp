// FreeCAD tool bits (.fctb, JSON: name, shape "ballend.fcstd", parameter
// {Diameter: "6.00 mm", CuttingEdgeHeight, Length, ShankDiameter,
// CornerRadius or FlatRadius, CuttingEdgeAngle, TipDiameter, TaperAngle,
// TaperDiameter, Flutes}, attribute {Flutes, Chipload, Material ...}) and tool
// libraries (.fctl, JSON: {label, tools: [{nr, path}]}). The tapered
// ball-nose's TaperAngle and the V-bit's CuttingEdgeAngle are included
// angles (FreeCAD's TaperedBallNose schema says "Included Taper angle").
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "cncstream/tooling/tool_import.hpp"
#include "import_common.hpp"
#include "import_json.hpp"
#include "lower_case.hpp"

namespace cncstream::tooling {

namespace detail_freecad {

using nlohmann::json;
using detail_import_json::JsonPlace;

// "6.00 mm", "0.25 in", "60.00 °", "60 deg", 6, "3": mm or degrees.
std::optional<double> quantity(const json& params, const char* key, const JsonPlace& place) {
  if (!params.contains(key) || params.at(key).is_null()) return std::nullopt;
  const json& v = params.at(key);
  if (v.is_number()) return v.get<double>();
  if (!v.is_string()) place.at(key).fail("expected a quantity such as \"6.00 mm\"");
  std::string s = v.get<std::string>();
  const char* b = s.data();
  const char* e = s.data() + s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(*b))) ++b;
  double x = 0;
  const auto [p, ec] = std::from_chars(b, e, x);
  if (ec != std::errc() || !std::isfinite(x)) place.at(key).fail(fmt::format("'{}' is not a quantity", s));
  std::string unit(p, e);
  unit.erase(std::remove_if(unit.begin(), unit.end(), [](unsigned char c) { return std::isspace(c); }), unit.end());
  if (unit.empty() || unit == "mm" || unit == "°" || unit == "deg") return x;
  if (unit == "in" || unit == "\"") return x * 25.4;
  if (unit == "cm") return x * 10;
  if (unit == "m") return x * 1000;
  place.at(key).fail(fmt::format("'{}': unknown unit '{}'", s, unit));
}

using detail_lower_case::lower;

// One bit; appends to r. `entry` names it in the report.
void read_bit(const json& j, const JsonPlace& p, const std::string& entry_prefix, int number, ImportResult& r) {
  if (!j.is_object()) p.fail("expected a tool bit object");
  const std::string name = p.str(j, "name").value_or("");
  std::string shape = lower(p.str(j, "shape").value_or(""));
  if (auto dot = shape.rfind('.'); dot != std::string::npos) shape.resize(dot);
  const std::string entry = fmt::format("{}'{}' ({})", entry_prefix, name, shape);
  const json empty = json::object();
  const json& params = j.contains("parameter") && j.at("parameter").is_object() ? j.at("parameter") : empty;
  const json& attrs = j.contains("attribute") && j.at("attribute").is_object() ? j.at("attribute") : empty;
  const JsonPlace pp = p.at("parameter"), ap = p.at("attribute");
  auto q = [&](const char* key) { return quantity(params, key, pp).value_or(0); };
  Tool t;
  t.number = number;
  ToolGeometry& g = t.geometry;
  g.diameter = q("Diameter");
  if (shape == "endmill") {
    g.shape = ToolShape::Flat;
  } else if (shape == "ballend") {
    g.shape = ToolShape::Ball;
  } else if (shape == "bullnose" || shape == "torus") {
    g.shape = ToolShape::Bull;
    g.corner_radius = q("CornerRadius");
    if (g.corner_radius == 0 && params.contains("FlatRadius")) g.corner_radius = g.diameter / 2 - q("FlatRadius");
    if (g.corner_radius <= 0) g.shape = ToolShape::Flat;
  } else if (shape == "v-bit" || shape == "vbit") {
    g.shape = ToolShape::VBit;
    g.angle = q("CuttingEdgeAngle");
    g.tip_diameter = q("TipDiameter");
  } else if (shape == "taperedballnose") {
    g.shape = ToolShape::TaperedBall;
    g.tip_diameter = g.diameter;
    g.angle = q("TaperAngle") / 2;  // included -> per side
    g.diameter = q("TaperDiameter");
  } else {
    r.skipped.push_back(fmt::format("{}: shape '{}' has no cutter here (endmill, ballend, bullnose, v-bit and "
                                    "taperedballnose are imported)",
                                    entry, shape));
    return;
  }
  t.name = name.empty() ? g.description() : name;
  t.flute_length = q("CuttingEdgeHeight");
  t.overall_length = q("Length");
  t.shank_diameter = q("ShankDiameter");
  std::optional<double> flutes = quantity(params, "Flutes", pp);
  if (!flutes) flutes = quantity(attrs, "Flutes", ap);
  if (flutes) t.flutes = static_cast<int>(std::lround(*flutes));
  std::string extra;
  if (const auto cl = quantity(attrs, "Chipload", ap); cl && *cl > 0) {
    CuttingData c;
    c.material = ap.str(attrs, "Material").value_or("default");
    c.chip_load = *cl;
    t.cutting.push_back(c);
    extra = fmt::format(", chip load {:g} mm for {}", *cl, c.material);
  }
  detail_import_common::accept_tool(r, std::move(t), entry, extra);
}

std::optional<std::string> read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace detail_freecad

ImportResult import_freecad_bit(std::string_view text, const std::string& source) {
  ImportResult r;
  r.format = "FreeCAD tool bit";
  const auto root = detail_import_json::parse_json(text, source);
  detail_freecad::read_bit(root, {source, ""}, "", 0, r);
  return r;
}

ImportResult import_freecad_library(std::string_view text, const std::string& source,
                                    const std::filesystem::path& library_dir) {
  using namespace detail_freecad;
  ImportResult r;
  r.format = "FreeCAD tool library";
  const json root = detail_import_json::parse_json(text, source);
  const JsonPlace top{source, ""};
  if (!root.is_object() || !root.contains("tools") || !root.at("tools").is_array())
    top.fail("expected an object with \"tools\": [{\"nr\": N, \"path\": \"BIT.fctb\"}]");
  const json& tools = root.at("tools");
  for (std::size_t k = 0; k < tools.size(); ++k) {
    const JsonPlace p = top.at("tools").at(k);
    const json& e = tools[k];
    if (!e.is_object()) p.fail("expected {\"nr\": N, \"path\": \"BIT.fctb\"}");
    const auto nr = p.num(e, "nr");
    const auto path = p.str(e, "path");
    if (!path) p.fail("no path to the tool bit");
    const int number = nr && *nr >= 1 && *nr <= 9999 ? static_cast<int>(*nr) : 0;
    const std::filesystem::path rel(*path);
    std::optional<std::string> bit;
    std::filesystem::path found;
    for (const auto& candidate : {rel.is_absolute() ? rel : library_dir / rel, library_dir / ".." / "Bit" / rel}) {
      if ((bit = detail_freecad::read_file(candidate))) {
        found = candidate;
        break;
      }
    }
    const std::string entry = fmt::format("{} T{} {}", p.pointer, number, *path);
    if (!bit) {
      r.skipped.push_back(entry + ": the tool bit file is not beside the library nor in ../Bit");
      continue;
    }
    const auto bit_json = detail_import_json::parse_json(*bit, found.string());
    read_bit(bit_json, {found.string(), ""}, fmt::format("{} T{} ", p.pointer, number), number, r);
  }
  return r;
}

}  // namespace cncstream::tooling
