// The tool library's TOML file: read with toml++ (behind the project's guard
// for text toml++ 3.3 misbehaves on), written by hand so that the file reads
// well and keeps a comment with each tool's shape in words.
#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "cncstream/tooling/tool_library.hpp"
#include "toml_read.hpp"

namespace cncstream::tooling {

namespace detail_library_toml {

struct Place {
  const std::string& source;
  [[noreturn]] void fail(const toml::node& n, const std::string& what) const {
    const auto line = n.source().begin.line;
    throw std::invalid_argument(line ? fmt::format("{}:{}: {}", source, line, what) : fmt::format("{}: {}", source, what));
  }
};

struct Fields {
  const Place& place;
  const toml::table& table;
  std::string prefix;

  void known(std::initializer_list<const char*> keys) const {
    for (const auto& [k, v] : table) {
      bool ok = false;
      for (const char* key : keys) ok = ok || k.str() == key;
      if (!ok) place.fail(v, fmt::format("{}{}: unknown key", prefix, k.str()));
    }
  }
  std::optional<std::string> str(const char* key) const {
    const auto* n = table.get(key);
    if (!n) return std::nullopt;
    if (!n->is_string()) place.fail(*n, fmt::format("{}{}: expected a string", prefix, key));
    return n->as_string()->get();
  }
  std::optional<double> number(const char* key) const {
    const auto* n = table.get(key);
    if (!n) return std::nullopt;
    if (n->is_integer()) return double(n->as_integer()->get());
    if (n->is_floating_point()) return n->as_floating_point()->get();
    place.fail(*n, fmt::format("{}{}: expected a number", prefix, key));
  }
  const toml::node* node(const char* key) const { return table.get(key); }
};

std::string quoted(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      o += fmt::format("\\u{:04x}", static_cast<unsigned>(c));
      continue;
    }
    o += c;
  }
  return o + "\"";
}

std::string num(double v) {
  std::string s = fmt::format("{:.10g}", v);
  return s;
}

}  // namespace detail_library_toml

ToolLibrary parse_tool_library(std::string_view text, const std::string& source) {
  using namespace detail_library_toml;
  const toml::table root = detail_toml_read::parse_toml(text, source);
  const Place place{source};
  Fields top{place, root, ""};
  top.known({"tool"});
  ToolLibrary lib;
  const auto* tools = root.get("tool");
  if (!tools) return lib;
  const auto* arr = tools->as_array();
  if (!arr) place.fail(*tools, "tool: expected [[tool]] tables");
  for (const auto& e : *arr) {
    const auto* t = e.as_table();
    if (!t) place.fail(e, "tool: expected a table");
    Fields f{place, *t, "tool."};
    f.known({"number", "name", "shape", "flutes", "flute_length", "overall_length", "stick_out", "shank_diameter",
             "length_offset", "notes", "cutting"});
    Tool tool;
    const auto number = f.number("number");
    if (!number) place.fail(e, "tool: no number");
    if (*number != std::floor(*number) || *number < 1 || *number > 9999)
      place.fail(*f.node("number"), "tool.number: expected a whole number 1..9999");
    tool.number = static_cast<int>(*number);
    tool.name = f.str("name").value_or("");
    const auto shape = f.str("shape");
    if (!shape) place.fail(e, fmt::format("tool {}: no shape (a spec such as ball:3.175 or taper:1:5:3.175)", tool.number));
    try {
      tool.geometry = parse_tool_spec(*shape);
    } catch (const std::invalid_argument& err) {
      place.fail(*f.node("shape"), fmt::format("tool {}: {}", tool.number, err.what()));
    }
    if (const auto v = f.number("flutes")) {
      if (*v != std::floor(*v)) place.fail(*f.node("flutes"), "tool.flutes: expected a whole number");
      tool.flutes = static_cast<int>(*v);
    }
    tool.flute_length = f.number("flute_length").value_or(0);
    tool.overall_length = f.number("overall_length").value_or(0);
    tool.stick_out = f.number("stick_out").value_or(0);
    tool.shank_diameter = f.number("shank_diameter").value_or(0);
    tool.length_offset = f.number("length_offset").value_or(0);
    tool.notes = f.str("notes").value_or("");
    if (const auto* cn = f.node("cutting")) {
      const auto* ca = cn->as_array();
      if (!ca) place.fail(*cn, "tool.cutting: expected [[tool.cutting]] tables");
      for (const auto& ce : *ca) {
        const auto* ct = ce.as_table();
        if (!ct) place.fail(ce, "tool.cutting: expected a table");
        Fields c{place, *ct, "tool.cutting."};
        c.known({"material", "rpm", "feed", "plunge_feed", "chip_load", "surface_speed", "stepdown", "stepover"});
        CuttingData d;
        d.material = c.str("material").value_or("");
        for_each_value(d, [&](const char* key, std::optional<double>& v) { v = c.number(key); });
        tool.cutting.push_back(d);
      }
    }
    try {
      lib.put(tool, false);
    } catch (const std::invalid_argument& err) {
      place.fail(e, err.what());
    }
  }
  return lib;
}

std::string format_tool_library(const ToolLibrary& library) {
  using namespace detail_library_toml;
  std::string o =
      "# cncstream tool library. Shapes: flat:D, ball:D, bull:D:r, vbit:ANGLE:D[:TIP_W] (included angle),\n"
      "# taper:TIP_D:ANGLE[:TOP_D] (angle per side); mm and degrees. Lengths 0 or absent: not known.\n";
  for (const Tool& t : library.tools) {
    o += fmt::format("\n[[tool]]\n# {}\nnumber = {}\nname = {}\nshape = {}\nflutes = {}\n", t.geometry.description(),
                     t.number, quoted(t.name), quoted(t.geometry.spec()), t.flutes);
    auto length = [&](const char* key, double v) {
      if (v > 0) o += fmt::format("{} = {}\n", key, num(v));
    };
    length("flute_length", t.flute_length);
    length("overall_length", t.overall_length);
    length("stick_out", t.stick_out);
    length("shank_diameter", t.shank_diameter);
    if (t.length_offset != 0) o += fmt::format("length_offset = {}\n", num(t.length_offset));
    if (!t.notes.empty()) o += fmt::format("notes = {}\n", quoted(t.notes));
    for (const auto& c : t.cutting) {
      o += fmt::format("[[tool.cutting]]\nmaterial = {}\n", quoted(c.material));
      for_each_value(c, [&](const char* key, const std::optional<double>& v) {
        if (v) o += fmt::format("{} = {}\n", key, num(*v));
      });
    }
  }
  return o;
}

ToolLibrary load_tool_library(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return {};
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": cannot open for reading");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_tool_library(text.str(), path.string());
}

}  // namespace cncstream::tooling
