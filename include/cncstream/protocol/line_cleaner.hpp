#pragma once
// Prepares G-code file lines for sending: strips comments and (for the GRBL
// family) whitespace so the byte cost is what the controller stores, checks
// the length against the profile before anything is sent, and marks lines
// that write EEPROM/flash (they must be sent one at a time).
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cncstream::protocol {

struct CleanOptions {
  bool strip_whitespace = true;  // GRBL drops spaces anyway; Marlin keeps them (M117 text)
  bool reject_realtime_chars = true;  // GRBL acts on '?', '!', '~' wherever they appear
};

// Removes "( ... )" and "; ..." comments, a leading "/" is kept (block delete
// is the controller's business), "%" demarcation lines become empty.
// Returns nullopt and sets `error` for an unclosed "(" comment.
std::optional<std::string> clean_gcode_line(std::string_view raw, const CleanOptions& opt = {},
                                            std::string* error = nullptr);

// $n=..., $I=..., $Nn=..., $RST=..., G10 L2/L20, G28.1, G30.1.
bool is_persistent_write(std::string_view cleaned);

struct PreparedLine {
  long source_line = 0;  // 1-based line in the file; 0 for operator commands
  std::string text;      // cleaned, without newline; empty = nothing to send
  bool sync = false;     // persistent write: send alone and wait for the answer
  int tool_change = -1;  // >= 0: a tool change to this tool (0: unnamed), never sent
};

struct PreparedProgram {
  std::vector<PreparedLine> lines;   // one per file line, in order
  std::vector<std::string> errors;   // "<file>:<line>: ..." for every line that cannot be sent
  std::size_t sendable = 0;          // lines with text
};

// `max_length` is the controller's line limit without the newline.
PreparedProgram prepare_program(const std::vector<std::string>& file_lines, const std::string& file_name,
                                std::size_t max_length, const CleanOptions& opt = {});

// Reads a G-code file into lines (LF or CRLF); errors name the file.
std::vector<std::string> read_gcode_lines(const std::string& path);

}  // namespace cncstream::protocol
