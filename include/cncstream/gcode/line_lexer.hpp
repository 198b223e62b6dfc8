#pragma once
// GRBL's line filtering and word lexing.
//
// The firmware cleans each incoming line as it arrives: whitespace and control
// characters, '/' (block delete) and comments ('(...)' and ';' to end of
// line) are thrown away, lower case is upcased, and at most 79 characters are
// kept (one more sets the overflow flag -> error:11). The streamer counts the
// cleaned length + 1 per line; the simulator assembles lines byte by byte the
// same way, so both share LineAssembler.
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cncstream::gcode {

inline constexpr std::size_t kLineBufferSize = 80;  // GRBL LINE_BUFFER_SIZE (incl. NUL)
inline constexpr std::size_t kMaxLineChars = kLineBufferSize - 1;

struct CleanLine {
  std::string text;       // upper case, no spaces or comments
  bool overflow = false;  // more than kMaxLineChars characters survived cleaning
};

// Byte-by-byte line assembly, exactly as the firmware's main loop does it.
// Both '\n' and '\r' end a line (so "\r\n" makes an extra empty line).
class LineAssembler {
 public:
  // Returns the finished line when `c` is an end of line.
  std::optional<CleanLine> push(char c);
  void reset();
  std::size_t pending_chars() const { return line_.text.size(); }

 private:
  CleanLine line_;
  bool in_paren_comment_ = false;
  bool in_semicolon_comment_ = false;
};

// Cleans one line given without its end of line.
CleanLine clean_line(std::string_view raw);

// Bytes a GRBL streamer charges for sending `raw`: cleaned length + 1 ('\n').
// Counting the raw length is also safe (never smaller); this is the minimum.
std::size_t grbl_line_cost(std::string_view raw);

struct Word {
  char letter = 0;
  double value = 0;
  std::size_t column = 0;  // index of the letter in the cleaned line
};

struct LexResult {
  int status = 0;             // 0, or grbl error 1 (letter expected) / 2 (bad number)
  std::size_t error_column = 0;
  std::vector<Word> words;
};

// Splits a cleaned line into letter/number words starting at `start`.
// Numbers follow the firmware's read_float: optional sign, digits with at most
// one '.', at least one digit, no exponent.
LexResult lex_words(std::string_view cleaned, std::size_t start = 0);

// read_float on its own: parses at `pos`, advancing it; false when no number.
bool read_grbl_number(std::string_view s, std::size_t& pos, double& value);

}  // namespace cncstream::gcode
