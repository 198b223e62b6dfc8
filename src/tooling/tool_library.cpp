#include "cncstream/tooling/tool_library.hpp"
#include "lower_case.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdlib>
#include <stdexcept>

namespace cncstream::tooling {

namespace detail_library {

using detail_lower_case::lower;

std::string list_tools(const std::vector<const Tool*>& tools) {
  std::string out;
  for (const Tool* t : tools) out += fmt::format("{}T{} '{}' ({})", out.empty() ? "" : ", ", t->number, t->name,
                                                 t->geometry.spec());
  return out;
}

// "3", "T3", "t3": a tool number.
std::optional<int> tool_number(std::string_view text) {
  if (!text.empty() && (text[0] == 'T' || text[0] == 't')) text.remove_prefix(1);
  int n = 0;
  const auto [p, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
  if (text.empty() || ec != std::errc() || p != text.data() + text.size()) return std::nullopt;
  return n;
}

}  // namespace detail_library

const Tool* ToolLibrary::by_number(int number) const {
  for (const auto& t : tools)
    if (t.number == number) return &t;
  return nullptr;
}

void ToolLibrary::put(const Tool& tool, bool replace) {
  check_tool(tool);
  for (const auto& t : tools) {
    if (t.number == tool.number && !replace)
      throw std::invalid_argument(fmt::format("tool number {} is taken by '{}' (replace it, or use number {})",
                                              tool.number, t.name, free_number()));
    if (t.number != tool.number && detail_library::lower(t.name) == detail_library::lower(tool.name))
      throw std::invalid_argument(fmt::format("the name '{}' is taken by T{}", tool.name, t.number));
  }
  auto it = std::find_if(tools.begin(), tools.end(), [&](const Tool& t) { return t.number == tool.number; });
  if (it != tools.end()) *it = tool;
  else tools.push_back(tool);
  std::sort(tools.begin(), tools.end(), [](const Tool& a, const Tool& b) { return a.number < b.number; });
}

void ToolLibrary::remove(int number) {
  auto it = std::find_if(tools.begin(), tools.end(), [&](const Tool& t) { return t.number == number; });
  if (it == tools.end()) throw std::invalid_argument(fmt::format("no tool number {} in the library", number));
  tools.erase(it);
}

int ToolLibrary::free_number() const {
  int n = 1;
  while (by_number(n)) ++n;
  return n;
}

ToolChoice choose_tool(const ToolLibrary& library, std::string_view text) {
  using namespace detail_library;
  ToolChoice c;
  if (text.empty()) throw std::invalid_argument("no tool given: a library tool's number or name, or a spec such as ball:3.175");
  // A spec has a colon after a known shape's name; a tool's name may not start so.
  if (const auto colon = text.find(':'); colon != std::string_view::npos && shape_from_name(text.substr(0, colon))) {
    c.geometry = parse_tool_spec(text);
    return c;
  }
  std::vector<const Tool*> all;
  for (const auto& t : library.tools) all.push_back(&t);
  const std::string known =
      all.empty() ? std::string(" (the library is empty: `cncstream tools add` or `tools import`, or give a spec such as ball:3.175)")
                  : " (the library has: " + list_tools(all) + ")";
  if (const auto n = tool_number(text)) {
    const Tool* t = library.by_number(*n);
    if (!t) throw std::invalid_argument(fmt::format("no tool number {} in the library{}", *n, known));
    c.tool = t;
    c.geometry = t->geometry;
    return c;
  }
  const std::string want = lower(text);
  std::vector<const Tool*> contains;
  for (const Tool* t : all) {
    const std::string name = lower(t->name);
    if (name == want) {
      c.tool = t;
      c.geometry = t->geometry;
      return c;
    }
    if (name.find(want) != std::string::npos) contains.push_back(t);
  }
  if (contains.size() == 1) {
    c.tool = contains[0];
    c.geometry = contains[0]->geometry;
    return c;
  }
  if (contains.size() > 1)
    throw std::invalid_argument(fmt::format("tool '{}' is ambiguous: it names {}; give the number or the whole name",
                                            text, list_tools(contains)));
  throw std::invalid_argument(fmt::format("no tool named '{}' and it is not a spec (flat:D, ball:D, bull:D:r, "
                                          "vbit:ANGLE:D, taper:TIP_D:ANGLE:TOP_D){}",
                                          text, known));
}

std::filesystem::path default_tool_library_path() {
  if (const char* s = std::getenv("CNCSTREAM_TOOLS"); s && *s) return s;
  if (const char* s = std::getenv("XDG_STATE_HOME"); s && *s)
    return std::filesystem::path(s) / "cncstream" / "tools.toml";
  if (const char* h = std::getenv("HOME"); h && *h)
    return std::filesystem::path(h) / ".local" / "state" / "cncstream" / "tools.toml";
  return "cncstream-tools.toml";
}

std::string tool_line(const Tool& t) {
  std::string s = fmt::format("T{:<3} {:<28} {:<18} {} flute{}", t.number, t.name, t.geometry.spec(), t.flutes,
                              t.flutes == 1 ? "" : "s");
  if (t.stick_out > 0) s += fmt::format(", stick-out {:g} mm", t.stick_out);
  if (t.flute_length > 0) s += fmt::format(", flutes {:g} mm", t.flute_length);
  if (!t.cutting.empty()) {
    s += ", data for";
    for (std::size_t k = 0; k < t.cutting.size(); ++k) {
      s.append(k ? ", " : " ");
      s.append(t.cutting[k].material);
    }
  }
  return s;
}

}  // namespace cncstream::tooling
