#include "cncstream/protocol/modal_state.hpp"

#include <cctype>
#include <string>

namespace cncstream::protocol {

void apply_answered_line(gcode::ParserState& state, std::string_view line) {
  if (line.empty() || line.front() == '$') return;  // system commands and jogs carry no modal words
  // Marlin's lines keep their spaces; the interpreter reads cleaned text.
  std::string cleaned;
  cleaned.reserve(line.size());
  for (const char c : line)
    if (c != ' ' && c != '\t') cleaned.push_back(static_cast<char>(std::toupper(static_cast<unsigned char>(c))));
  auto r = gcode::execute_block(state, cleaned);
  if (r.ok()) state = r.state;  // a program end is applied by the interpreter
}

}  // namespace cncstream::protocol
