// Inputs the fuzzer found (tests/fuzz), kept as unit tests of the answer.
#include <gtest/gtest.h>

#include <string>

#include "cncstream/gcode/interpreter.hpp"

using namespace cncstream::gcode;

TEST(InterpreterFuzzRegressions, AValueBeyondIntIsAnErrorNotUndefinedBehaviour) {
  const std::string digits(72, '3');  // 3.3e71: overflowed the int conversion
  for (const std::string& line : {"G" + digits, "M" + digits, "G1X1N" + digits, "T" + digits}) {
    const BlockResult r = execute_block(ParserState{}, line);
    EXPECT_FALSE(r.ok()) << line;
  }
  const std::string negative = "G-" + digits;
  EXPECT_FALSE(execute_block(ParserState{}, negative).ok());
  // A dwell takes any P, as GRBL's does (a float, no range check).
  EXPECT_TRUE(execute_block(ParserState{}, "G4P" + digits).ok());
}
