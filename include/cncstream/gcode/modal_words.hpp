#pragma once
// The one modal state (gcode::ParserState) written as the words that set it,
// and read back from them: how the journal stores it and how it is shown.
// Words are the program's own (F in the program's units).
#include <string>

#include "cncstream/gcode/interpreter.hpp"

namespace cncstream::gcode {

struct ModalWords {
  std::string units = "G21", distance = "G90", plane = "G17", wcs = "G54", motion = "G0";
  std::string feed_mode = "G94", spindle = "M5", coolant = "M9";  // coolant: M9, M7, M8 or M7M8
  double feed = 0;           // program units per minute (or the G93 value)
  double spindle_speed = 0;  // rpm
  int tool = 0;
};

ModalWords modal_words(const ParserState& s);
// The state those words set, from power-up defaults. Throws
// std::invalid_argument naming the word the interpreter refuses.
ParserState modal_from_words(const ModalWords& w);
// {"units":"G21",...}: for logs, the journal's display and the daemon's API.
std::string modal_json(const ParserState& s);

}  // namespace cncstream::gcode
