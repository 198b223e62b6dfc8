#include "cncstream/protocol/line_cleaner.hpp"

#include <cctype>
#include <charconv>
#include <fstream>
#include <stdexcept>

namespace cncstream::protocol {

std::optional<std::string> clean_gcode_line(std::string_view raw, const CleanOptions& opt, std::string* error) {
  std::string out;
  out.reserve(raw.size());
  bool in_paren = false;
  for (std::size_t i = 0; i < raw.size(); ++i) {
    const char c = raw[i];
    if (in_paren) {
      if (c == ')') in_paren = false;
      continue;
    }
    if (c == '(') {
      in_paren = true;
      continue;
    }
    if (c == ';') break;
    if (c == '\r' || c == '\n') continue;
    if (opt.strip_whitespace && (c == ' ' || c == '\t')) continue;
    out.push_back(c);
  }
  if (in_paren) {
    if (error) *error = "comment '(' is not closed on this line";
    return std::nullopt;
  }
  // Trim what whitespace remains (Marlin mode keeps inner spaces only).
  while (!out.empty() && (out.back() == ' ' || out.back() == '\t')) out.pop_back();
  std::size_t lead = 0;
  while (lead < out.size() && (out[lead] == ' ' || out[lead] == '\t')) ++lead;
  out.erase(0, lead);
  if (out == "%") out.clear();
  return out;
}

namespace {

struct Word {
  char letter;
  double value;
};

// Letter+number words of a cleaned G-code line; stops at anything else.
std::vector<Word> words(std::string_view s) {
  std::vector<Word> out;
  std::size_t i = 0;
  while (i < s.size()) {
    const char l = static_cast<char>(std::toupper(static_cast<unsigned char>(s[i])));
    if (l == ' ' || l == '\t') {
      ++i;
      continue;
    }
    if (l < 'A' || l > 'Z') break;
    ++i;
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    std::size_t j = i;
    while (j < s.size() && (std::isdigit(static_cast<unsigned char>(s[j])) || s[j] == '.' || s[j] == '-' || s[j] == '+'))
      ++j;
    double v = 0;
    auto num = s.substr(i, j - i);
    if (!num.empty() && num.front() == '+') num.remove_prefix(1);
    if (std::from_chars(num.data(), num.data() + num.size(), v).ec != std::errc{}) break;
    out.push_back({l, v});
    i = j;
  }
  return out;
}

bool near(double a, double b) { return a > b - 1e-6 && a < b + 1e-6; }

}  // namespace

bool is_persistent_write(std::string_view s) {
  if (s.empty()) return false;
  if (s.front() == '$') {
    std::string up;
    for (char c : s) up.push_back(static_cast<char>(std::toupper(static_cast<unsigned char>(c))));
    std::string_view u(up);
    if (u.substr(0, 3) == "$J=") return false;
    if (u.substr(0, 5) == "$RST=" || u.substr(0, 3) == "$I=") return true;
    std::size_t i = 1;
    if (i < u.size() && u[i] == 'N') ++i;  // $N0=, $N1= startup lines
    const std::size_t digits = i;
    while (i < u.size() && std::isdigit(static_cast<unsigned char>(u[i]))) ++i;
    return i > digits && i < u.size() && u[i] == '=';
  }
  bool g10 = false, l2or20 = false;
  for (const auto& w : words(s)) {
    if (w.letter == 'G' && (near(w.value, 28.1) || near(w.value, 30.1))) return true;
    if (w.letter == 'G' && near(w.value, 10)) g10 = true;
    if (w.letter == 'L' && (near(w.value, 2) || near(w.value, 20))) l2or20 = true;
  }
  return g10 && l2or20;
}

PreparedProgram prepare_program(const std::vector<std::string>& file_lines, const std::string& file_name,
                                std::size_t max_length, const CleanOptions& opt) {
  PreparedProgram p;
  p.lines.reserve(file_lines.size());
  for (std::size_t i = 0; i < file_lines.size(); ++i) {
    PreparedLine l;
    l.source_line = static_cast<long>(i + 1);
    std::string err;
    auto cleaned = clean_gcode_line(file_lines[i], opt, &err);
    const std::string where = file_name + ":" + std::to_string(i + 1) + ": ";
    if (!cleaned) {
      p.errors.push_back(where + err);
    } else {
      l.text = std::move(*cleaned);
      if (l.text.size() > max_length)
        p.errors.push_back(where + "line is " + std::to_string(l.text.size()) +
                           " characters after removing comments and spaces; the controller accepts at most " +
                           std::to_string(max_length) + " (it would answer error:11 and skip it): '" + l.text + "'");
      for (unsigned char c : l.text)
        if (c < 0x20 || c >= 0x7F || (opt.reject_realtime_chars && (c == '?' || c == '!' || c == '~'))) {
          p.errors.push_back(where + "character 0x" + "0123456789ABCDEF"[c >> 4] + "0123456789ABCDEF"[c & 15] +
                             " is a real-time command or not printable; the controller would act on it at once");
          break;
        }
      l.sync = is_persistent_write(l.text);
      if (!l.text.empty()) ++p.sendable;
    }
    p.lines.push_back(std::move(l));
  }
  return p;
}

std::vector<std::string> read_gcode_lines(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open G-code file");
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(std::move(line));
  }
  if (in.bad()) throw std::runtime_error(path + ": read error after line " + std::to_string(lines.size()));
  return lines;
}

}  // namespace cncstream::protocol
