#include "cncstream/gcode/program_pause.hpp"

#include <cctype>

namespace cncstream::gcode {

namespace {

// The line without its comments ("(...)" and ";..."), upper case, no spaces;
// the comments' text into `comments`.
std::string words_of(const std::string& line, std::string* comments = nullptr) {
  std::string words;
  bool in_paren = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (in_paren) {
      if (c == ')') {
        in_paren = false;
      } else if (comments) {
        comments->push_back(c);
      }
      continue;
    }
    if (c == '(') {
      in_paren = true;
      if (comments && !comments->empty()) comments->push_back(' ');
      continue;
    }
    if (c == ';') {
      if (comments) {
        if (!comments->empty()) comments->push_back(' ');
        comments->append(line, i + 1);
      }
      break;
    }
    if (!std::isspace(static_cast<unsigned char>(c))) words.push_back(static_cast<char>(std::toupper(static_cast<unsigned char>(c))));
  }
  return words;
}

bool only_t_word(const std::string& words) {
  if (words.size() < 2 || words[0] != 'T') return false;
  for (std::size_t i = 1; i < words.size(); ++i)
    if (!std::isdigit(static_cast<unsigned char>(words[i]))) return false;
  return true;
}

}  // namespace

bool has_no_words(const std::string& line) { return words_of(line).empty(); }

bool is_program_pause(const std::string& line) {
  const std::string w = words_of(line);
  for (std::size_t i = 0; i + 1 < w.size(); ++i) {
    if (w[i] != 'M') continue;
    std::size_t j = i + 1;
    while (j < w.size() && w[j] == '0') ++j;
    // M followed by zeros only, then a letter or the end: M0, M00.
    if (j > i + 1 && (j == w.size() || std::isalpha(static_cast<unsigned char>(w[j])))) return true;
  }
  return false;
}

std::optional<std::string> program_pause_note(const std::vector<std::string>& lines, std::size_t index) {
  if (index >= lines.size() || !is_program_pause(lines[index])) return std::nullopt;
  std::vector<std::string> notes;
  for (std::size_t k = index; k-- > 0;) {
    std::string comment;
    const std::string w = words_of(lines[k], &comment);
    if (!w.empty() && !only_t_word(w)) break;
    if (!comment.empty()) notes.push_back(std::move(comment));
  }
  std::string out;
  for (auto it = notes.rbegin(); it != notes.rend(); ++it) {
    if (!out.empty()) out.push_back(' ');
    out += *it;
  }
  return out;
}

}  // namespace cncstream::gcode
