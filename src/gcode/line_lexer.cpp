#include "cncstream/gcode/line_lexer.hpp"

#include <cmath>

namespace cncstream::gcode {

std::optional<CleanLine> LineAssembler::push(char ch) {
  const auto c = static_cast<unsigned char>(ch);
  if (c == '\n' || c == '\r') {
    CleanLine done = std::move(line_);
    reset();
    return done;
  }
  if (in_paren_comment_ || in_semicolon_comment_ || line_.overflow) {
    // Comment and overflow characters are thrown away; ')' ends a '(' comment.
    if (c == ')' && in_paren_comment_) in_paren_comment_ = false;
    return std::nullopt;
  }
  if (c <= ' ' || c == '/') return std::nullopt;
  if (c == '(') {
    in_paren_comment_ = true;
  } else if (c == ';') {
    in_semicolon_comment_ = true;
  } else if (line_.text.size() >= kMaxLineChars) {
    line_.overflow = true;
  } else if (c >= 'a' && c <= 'z') {
    line_.text.push_back(static_cast<char>(c - 'a' + 'A'));
  } else {
    line_.text.push_back(static_cast<char>(c));
  }
  return std::nullopt;
}

void LineAssembler::reset() {
  line_ = CleanLine{};
  in_paren_comment_ = false;
  in_semicolon_comment_ = false;
}

CleanLine clean_line(std::string_view raw) {
  LineAssembler a;
  for (char c : raw) {
    if (c == '\n' || c == '\r') continue;
    a.push(c);
  }
  return *a.push('\n');
}

std::size_t grbl_line_cost(std::string_view raw) {
  const CleanLine c = clean_line(raw);
  return (c.overflow ? kMaxLineChars + 1 : c.text.size()) + 1;
}

bool read_grbl_number(std::string_view s, std::size_t& pos, double& value) {
  std::size_t i = pos;
  bool negative = false;
  if (i < s.size() && (s[i] == '-' || s[i] == '+')) {
    negative = s[i] == '-';
    ++i;
  }
  double intpart = 0, frac = 0, scale = 1;
  bool seen_point = false;
  std::size_t digits = 0;
  while (i < s.size()) {
    const char c = s[i];
    if (c >= '0' && c <= '9') {
      ++digits;
      if (seen_point) {
        scale *= 0.1;
        frac += (c - '0') * scale;
      } else {
        intpart = intpart * 10 + (c - '0');
      }
    } else if (c == '.' && !seen_point) {
      seen_point = true;
    } else {
      break;
    }
    ++i;
  }
  if (digits == 0) return false;
  value = (intpart + frac) * (negative ? -1 : 1);
  pos = i;
  return true;
}

LexResult lex_words(std::string_view cleaned, std::size_t start) {
  LexResult r;
  std::size_t i = start;
  while (i < cleaned.size()) {
    const char letter = cleaned[i];
    if (letter < 'A' || letter > 'Z') {
      r.status = 1;
      r.error_column = i;
      return r;
    }
    Word w;
    w.letter = letter;
    w.column = i;
    ++i;
    if (!read_grbl_number(cleaned, i, w.value)) {
      r.status = 2;
      r.error_column = i;
      return r;
    }
    r.words.push_back(w);
  }
  return r;
}

}  // namespace cncstream::gcode
