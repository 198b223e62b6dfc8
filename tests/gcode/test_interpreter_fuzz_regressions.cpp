// Inputs the fuzzer found (tests/fuzz), kept as unit tests of the answer.
#include <gtest/gtest.h>

#include <limits>
#include <string>

#include "cncstream/gcode/arc_segments.hpp"
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

TEST(InterpreterFuzzRegressions, ARadiusArcThatDoesNotMoveInItsPlaneIsAnInvalidTarget) {
  // Found by fuzz_gcode: from (10, 10, -1) to (10, 10, 0) with R, a helix
  // with no turn: the centre's formula divided by zero and the arc's centre
  // was NaN (then undefined behaviour where its chords were counted).
  const BlockResult to_start = execute_block(ParserState{}, "G1X10Y10Z-1F100");
  ASSERT_TRUE(to_start.ok());
  EXPECT_EQ(execute_block(to_start.state, "G3X10Y10Z0R1").status, 33);
  EXPECT_EQ(execute_block(to_start.state, "G3X10Y10R1").status, 33);
  EXPECT_TRUE(execute_block(to_start.state, "G3X12Y10Z0R1").ok());
  // Coordinates whose arithmetic overflows leave no arc either.
  const std::string big = "1" + std::string(300, '0');  // 1e300
  const BlockResult far = execute_block(ParserState{}, "G1X" + big + "Y" + big + "F100");
  ASSERT_TRUE(far.ok());
  EXPECT_EQ(execute_block(far.state, "G2X-" + big + "Y-" + big + "R" + big).status, 33);
}

TEST(InterpreterFuzzRegressions, AnArcOfKilometresIsCutInAtMostGrblsNumberOfChords) {
  ArcMove arc;
  arc.from = {1e9, 0, 0};
  arc.to = {-1e9, 0, 0};
  arc.radius = 1e9;  // a semicircle of a thousand kilometres: 2.5e10 chords at 0.002 mm
  const auto points = segment_arc(arc, 0.002);
  EXPECT_EQ(points.size(), 65535u);
  EXPECT_EQ(points.back().x, -1e9);
  arc.radius = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(segment_arc(arc, 0.002).size(), 1u);  // straight to the target
}

TEST(InterpreterFuzzRegressions, AG10PBeyondIntIsAnUnsupportedCoordinateSystem) {
  // Found by fuzz_gcode: P888888888880 overflowed the int it was converted to.
  EXPECT_EQ(execute_block(ParserState{}, "G10L20P888888888880X0Y0").status, 29);
  EXPECT_EQ(execute_block(ParserState{}, "G10L20P7X0").status, 29);
  EXPECT_TRUE(execute_block(ParserState{}, "G10L20P6X0").ok());
}
