#include "cncstream/gcode/tool_change_line.hpp"

#include <cctype>
#include <charconv>

#include "cncstream/gcode/program_pause.hpp"

namespace cncstream::gcode {

namespace {

// The words of a line, upper case, no blanks, comments left out.
std::string tool_line_words(const std::string& line) {
  std::string w;
  bool paren = false;
  for (const char c : line) {
    if (paren) {
      paren = c != ')';
      continue;
    }
    if (c == '(') {
      paren = true;
      continue;
    }
    if (c == ';') break;
    if (!std::isspace(static_cast<unsigned char>(c))) w.push_back(static_cast<char>(std::toupper(static_cast<unsigned char>(c))));
  }
  return w;
}

// The integer after each occurrence of `letter` (the last one wins), if any.
std::optional<int> word_value(const std::string& words, char letter, bool* other_words = nullptr) {
  std::optional<int> v;
  for (std::size_t i = 0; i < words.size(); ++i) {
    if (!std::isalpha(static_cast<unsigned char>(words[i]))) continue;
    std::size_t j = i + 1;
    while (j < words.size() && (std::isdigit(static_cast<unsigned char>(words[j])) || words[j] == '.')) ++j;
    if (words[i] == letter) {
      int n = 0;
      const auto r = std::from_chars(words.data() + i + 1, words.data() + j, n);
      if (r.ec == std::errc()) v = n;
    } else if (other_words) {
      *other_words = true;
    }
    i = j - 1;
  }
  return v;
}

bool has_m(const std::string& words, int m) {
  for (std::size_t i = 0; i < words.size(); ++i) {
    if (words[i] != 'M') continue;
    std::size_t j = i + 1;
    while (j < words.size() && std::isdigit(static_cast<unsigned char>(words[j]))) ++j;
    if (j == i + 1) continue;
    // "M6.1" is another code, not M6.
    if (j < words.size() && words[j] == '.') continue;
    int n = -1;
    std::from_chars(words.data() + i + 1, words.data() + j, n);
    if (n == m) return true;
  }
  return false;
}

}  // namespace

std::vector<ToolChangeLine> find_tool_changes(const std::vector<std::string>& lines) {
  std::vector<ToolChangeLine> out;
  int t_in_force = 0;
  std::optional<std::size_t> t_only_line;  // the last line with words was a lone T word
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string w = tool_line_words(lines[i]);
    if (w.empty()) continue;
    bool others = false;
    const auto t = word_value(w, 'T', &others);
    if (t) t_in_force = *t;
    const bool m6 = has_m(w, 6);
    const bool m0 = has_m(w, 0);
    if (m6 || (m0 && (t || t_only_line))) {
      ToolChangeLine c;
      c.index = i;
      c.tool = t_in_force;
      c.note = program_pause_note(lines, i).value_or("");
      out.push_back(std::move(c));
    }
    // A lone T word (an M0 may follow it).
    t_only_line = (t && !others) ? std::optional<std::size_t>(i) : std::nullopt;
  }
  return out;
}

int first_tool(const std::vector<std::string>& lines) {
  const auto changes = find_tool_changes(lines);
  const std::size_t end = changes.empty() ? lines.size() : changes.front().index;
  for (std::size_t i = 0; i < end; ++i)
    if (const auto t = word_value(tool_line_words(lines[i]), 'T')) return *t;
  return 0;
}

}  // namespace cncstream::gcode
