// LinuxCNC tool table (tool.tbl): a line per tool, "T<n> P<pocket> Z<length>
// D<diameter> ;comment" (and X Y A B C U V W I J Q, kept out here), in
// machine units, no shape and no feeds. The shape is taken from the
// comment where it names one (ball, bull), else flat, and the report says so.
#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "cncstream/tooling/tool_import.hpp"
#include "lower_case.hpp"

namespace cncstream::tooling {

namespace detail_linuxcnc {

using detail_lower_case::lower;

std::string trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return std::string(s);
}

}  // namespace detail_linuxcnc

ImportResult import_linuxcnc_table(std::string_view text, const std::string& source, bool inch) {
  using namespace detail_linuxcnc;
  ImportResult r;
  r.format = "LinuxCNC tool table";
  const double scale = inch ? 25.4 : 1;
  std::size_t line_no = 0;
  while (!text.empty()) {
    ++line_no;
    const auto nl = text.find('\n');
    std::string_view line = text.substr(0, nl);
    text = nl == std::string_view::npos ? std::string_view() : text.substr(nl + 1);
    std::string comment;
    if (const auto semi = line.find(';'); semi != std::string_view::npos) {
      comment = trim(line.substr(semi + 1));
      line = line.substr(0, semi);
    }
    std::optional<double> words[26];
    std::size_t i = 0;
    bool any = false;
    while (i < line.size()) {
      const unsigned char c = static_cast<unsigned char>(line[i]);
      if (std::isspace(c)) {
        ++i;
        continue;
      }
      const char letter = static_cast<char>(std::toupper(c));
      if (!std::strchr("TPXYZABCUVWDIJQ", letter) || letter == '\0')
        throw std::invalid_argument(fmt::format("{}:{}: unexpected '{}' at column {} (expected T, P, X, Y, Z, A, B, C, "
                                                "U, V, W, D, I, J, Q or a ';' comment)",
                                                source, line_no, line[i], i + 1));
      std::size_t j = i + 1;
      while (j < line.size() && !std::isspace(static_cast<unsigned char>(line[j]))) ++j;
      const std::string_view value = line.substr(i + 1, j - i - 1);
      double v = 0;
      const char* b = value.data();
      if (!value.empty() && *b == '+') ++b;
      const auto [p, ec] = std::from_chars(b, value.data() + value.size(), v);
      if (value.empty() || ec != std::errc() || p != value.data() + value.size() || !std::isfinite(v))
        throw std::invalid_argument(
            fmt::format("{}:{}: '{}{}' at column {}: expected a number after {}", source, line_no, letter, value, i + 1, letter));
      if (words[letter - 'A'])
        throw std::invalid_argument(fmt::format("{}:{}: {} given twice", source, line_no, letter));
      words[letter - 'A'] = v;
      any = true;
      i = j;
    }
    if (!any) continue;  // blank or comment only
    const std::string entry = fmt::format("line {} {}", line_no, comment.empty() ? std::string("(no comment)") : fmt::format("'{}'", comment));
    const auto& tn = words['T' - 'A'];
    if (!tn) throw std::invalid_argument(fmt::format("{}:{}: a tool line without T", source, line_no));
    if (*tn != std::floor(*tn) || *tn < 0)
      throw std::invalid_argument(fmt::format("{}:{}: T{} is not a tool number", source, line_no, *tn));
    const int number = static_cast<int>(*tn);
    if (number == 0 || number > 9999) {
      r.skipped.push_back(fmt::format("{} T{}: T0 is the empty spindle; numbers go to 9999", entry, number));
      continue;
    }
    const double d = words['D' - 'A'].value_or(0) * scale;
    if (!(d > 0)) {
      r.skipped.push_back(fmt::format("{} T{}: no diameter (D)", entry, number));
      continue;
    }
    Tool t;
    t.number = number;
    const std::string lc = lower(comment);
    std::string assumed;
    if (lc.find("ball") != std::string::npos) {
      t.geometry.shape = ToolShape::Ball;
    } else {
      t.geometry.shape = ToolShape::Flat;
      if (lc.find("flat") == std::string::npos && lc.find("end mill") == std::string::npos &&
          lc.find("endmill") == std::string::npos)
        assumed = " (shape assumed flat: a tool table has none; edit it if not)";
    }
    t.geometry.diameter = d;
    t.name = comment.empty() ? fmt::format("T{} {}", number, t.geometry.description()) : comment;
    if (const auto& z = words['Z' - 'A']) t.length_offset = *z * scale;
    try {
      check_tool(t);
    } catch (const std::invalid_argument& e) {
      r.skipped.push_back(fmt::format("{}: {}", entry, e.what()));
      continue;
    }
    r.understood.push_back(fmt::format("{} -> T{} {}{}{}", entry, number, t.geometry.spec(),
                                       t.length_offset != 0 ? fmt::format(", length offset {:g} mm", t.length_offset)
                                                            : std::string(),
                                       assumed));
    r.tools.push_back(std::move(t));
  }
  return r;
}

}  // namespace cncstream::tooling
