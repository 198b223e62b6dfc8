#include "cncstream/protocol/toml_guard.hpp"

#include <cctype>
#include <stdexcept>
#include <string>

namespace cncstream::protocol {

namespace {

std::string cat_line(const std::string& source, std::size_t line) {
  std::string s = source;
  s.append(":").append(std::to_string(line));
  return s;
}

}  // namespace

// toml++ 3.3 (Debian bookworm's) misbehaves on some text instead of
// refusing it, each undefined behaviour in a release build, all found by
// tests/fuzz: assertions on a table header whose key does not start with a
// key character ("[[)achine]]"), on an array element starting with '}'
// ("a = [}]") and on a date followed by a space and a lone digit
// ("2051-06-01 0 "); an unreachable branch in its whitespace test, which it
// runs on any character outside strings and comments ("name = \xC3\xA9"),
// through a quote inside a bare value ("a = 1\"\xC3\xA9\""), and on the first
// character after a backslash in a string (an escape, or the blanks a
// line-ending backslash skips, which is valid TOML). TOML allows characters
// beyond ASCII only in strings and comments, so the text is checked for all
// of these first, naming the line. A quote starts a string only where TOML
// allows one: where a key starts (a line, after '.', or after '{' or ',' in
// an inline table) or a value (after '=', or as an array's element).
void check_toml_text(std::string_view text, const std::string& source) {
  enum class In { Code, Comment, Basic, Literal, MultiBasic, MultiLiteral, BareValue } in = In::Code;
  std::size_t line = 1;
  std::string open;     // the arrays ('[') and inline tables ('{') open around here
  bool blank = true;    // no code yet on this line
  std::size_t bare_start = 0;  // where the bare value being read starts
  char prev = 0;        // the last character of code on this line, blanks aside
  char last = 0;        // the same across lines and comments
  auto refuse = [&](const char* why) { throw std::invalid_argument(cat_line(source, line) + ": " + why); };
  auto starts = [&](std::size_t i, std::string_view s) { return text.substr(i, s.size()) == s; };
  auto beyond_ascii = [](char c) { return static_cast<unsigned char>(c) >= 0x80; };
  auto in_array = [&] { return !open.empty() && open.back() == '['; };
  // After a multi-line string's closing quotes: up to two more belong to the string.
  auto close_multi = [&](std::size_t& i, char q) {
    i += 2;
    for (int extra = 0; extra < 2 && i + 1 < text.size() && text[i + 1] == q; ++extra) ++i;
    in = In::Code;
    prev = last = q;
  };
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
      blank = true;
      if (in != In::MultiBasic && in != In::MultiLiteral) in = In::Code;
      continue;
    }
    // A bare value (a number, a boolean, a date, or garbage) runs to the next
    // terminator, quotes and brackets included: toml++ scans it so.
    if (in == In::BareValue) {
      if (c != ' ' && c != '\t' && c != ',' && c != ']' && c != '}' && c != '#') {
        if (beyond_ascii(c)) refuse("a character beyond ASCII outside a string or comment (quote the value)");
        prev = last = c;
        continue;
      }
      // A date, a space and one digit: toml++ takes it for a date-time and
      // asserts at the terminator after the digit.
      const std::string_view token = text.substr(bare_start, i - bare_start);
      if (c == ' ' && token.size() == 10 && token[4] == '-' && token[7] == '-' && i + 2 < text.size() &&
          std::isdigit(static_cast<unsigned char>(text[i + 1])) &&
          std::string_view(" \t\r\n\v\f,]}#").find(text[i + 2]) != std::string_view::npos)
        refuse("a date followed by a lone digit (write the time as HH:MM:SS)");
      in = In::Code;
    }
    switch (in) {
      case In::Comment:
      case In::BareValue: break;
      case In::Basic:
      case In::MultiBasic:
        if (c == '\\') {
          // An escape, or a line-ending backslash whose blanks and newlines toml++ skips
          // with its whitespace test.
          std::size_t k = i + 1;
          while (k < text.size() && (text[k] == ' ' || text[k] == '\t' || text[k] == '\r' || text[k] == '\n')) ++k;
          if (k < text.size() && beyond_ascii(text[k]))
            refuse("a character beyond ASCII right after a backslash (toml++ 3.3 cannot read it)");
          if (i + 1 < text.size() && text[i + 1] == '\n') ++line;
          ++i;
        } else if (in == In::Basic && c == '"') {
          in = In::Code;
          prev = last = c;
        } else if (in == In::MultiBasic && starts(i, "\"\"\"")) {
          close_multi(i, '"');
        }
        break;
      case In::Literal:
        if (c == '\'') {
          in = In::Code;
          prev = last = c;
        }
        break;
      case In::MultiLiteral:
        if (starts(i, "'''")) close_multi(i, '\'');
        break;
      case In::Code: {
        if (beyond_ascii(c)) refuse("a character beyond ASCII outside a string or comment (quote the value)");
        if (c == ' ' || c == '\t' || c == '\r') break;
        if (c == '#') {
          in = In::Comment;  // a comment is no code: prev and last stay
          break;
        }
        // Where a value starts: after '=', or as an array's element.
        const bool value = (!blank && prev == '=') || (in_array() && (last == '[' || last == ','));
        const bool key = !value && (blank || prev == '.' || prev == '[' || ((prev == '{' || prev == ',') && !open.empty()));
        if ((c == '"' || c == '\'') && (value || key)) {
          const bool multi = starts(i, c == '"' ? "\"\"\"" : "'''");
          in = c == '"' ? (multi ? In::MultiBasic : In::Basic) : (multi ? In::MultiLiteral : In::Literal);
          if (multi) i += 2;
        } else if (c == '[' && blank && open.empty()) {
          std::size_t k = i + 1;
          if (k < text.size() && text[k] == '[') ++k;
          while (k < text.size() && (text[k] == ' ' || text[k] == '\t')) ++k;
          const char h = k < text.size() ? text[k] : '\0';
          const bool key_char = (h >= 'A' && h <= 'Z') || (h >= 'a' && h <= 'z') || (h >= '0' && h <= '9') ||
                                h == '_' || h == '-' || h == '"' || h == '\'';
          if (!key_char && h != ']') refuse("a table header must start with a key (a letter, digit, _, - or a quote)");
        } else if (c == '}' && in_array() && (last == '[' || last == ',')) {
          refuse("'}' where an array's element belongs");
        } else if ((c == '[' || c == '{') && value) {
          open.push_back(c);
        } else if ((c == ']' && in_array()) || (c == '}' && !open.empty() && open.back() == '{')) {
          open.pop_back();
        } else if (value && c != ',' && c != ']' && c != '}' && c != '=') {
          in = In::BareValue;
          bare_start = i;
        }
        prev = last = c;
        blank = false;
        break;
      }
    }
  }
}

}  // namespace cncstream::protocol
