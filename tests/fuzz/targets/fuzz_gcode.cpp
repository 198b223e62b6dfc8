// G-code text -> the lexer, the interpreter (line by line, as the streamer's
// modal tracking does) and the whole-program trace with its time estimate.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

#include "cncstream/gcode/interpreter.hpp"
#include "cncstream/gcode/line_lexer.hpp"
#include "cncstream/gcode/program.hpp"

using namespace cncstream::gcode;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  ParserState state;
  for (const auto line : split_lines(text)) {
    (void)grbl_line_cost(line);
    const CleanLine c = clean_line(line);
    (void)lex_words(c.text);
    const BlockResult r = execute_block(state, c.text);
    if (r.ok()) state = r.state;
  }
  try {
    const ProgramTrace trace = trace_program(text);
    MotionLimits limits;
    (void)estimate_program_time(trace, limits);
  } catch (const std::exception&) {
    // A program the trace refuses is refused with a reason, never a crash.
  }
  return 0;
}
