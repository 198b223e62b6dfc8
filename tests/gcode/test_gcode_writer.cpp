#include <gtest/gtest.h>

#include <cmath>

#include "cncstream/gcode/gcode_writer.hpp"

using namespace cncstream;

TEST(GcodeNumber, PlainDecimalsNeverExponent) {
  EXPECT_EQ(format_gcode_number(1e-7), "0");
  EXPECT_EQ(format_gcode_number(-1e-7), "0");
  EXPECT_EQ(format_gcode_number(12.5), "12.5");
  EXPECT_EQ(format_gcode_number(-3.14159), "-3.142");
  EXPECT_EQ(format_gcode_number(100.0), "100");
  EXPECT_EQ(format_gcode_number(123456.0004), "123456");
  EXPECT_THROW(format_gcode_number(NAN), std::invalid_argument);
  for (double v : {1e-12, 3.3e-5, 98765.4321, -0.0}) {
    const auto s = format_gcode_number(v);
    EXPECT_EQ(s.find_first_of("eE"), std::string::npos) << s;
  }
}

TEST(GcodeWriter, ModalWordsOnlyWhenChanged) {
  GcodeWriter w;
  w.rapid(std::nullopt, std::nullopt, 5.0);
  w.rapid(1.0, 2.0, std::nullopt);
  w.feed(1.0, 2.0, -1.0, 300);
  w.feed(2.0, 2.0, -1.0, 1000);
  w.feed(3.0, 2.0, -1.2, 1000);
  EXPECT_FALSE(w.feed(3.0, 2.0, -1.2, 1000));
  const std::vector<std::string> expect{"G0Z5", "X1Y2", "G1Z-1F300", "X2F1000", "X3Z-1.2"};
  EXPECT_EQ(w.lines(), expect);
  EXPECT_EQ(w.motion_lines(), 5u);
}

TEST(GcodeWriter, CommentsAreSafeAndShort) {
  GcodeWriter w;
  w.comment("part (v2): " + std::string(200, 'x') + " end");
  for (const auto& l : w.lines()) {
    EXPECT_LE(l.size(), 80u);
    EXPECT_EQ(l.front(), '(');
    EXPECT_EQ(l.back(), ')');
    EXPECT_EQ(l.substr(1, l.size() - 2).find_first_of("()"), std::string::npos) << l;
  }
  EXPECT_THROW(w.line(std::string(81, 'X')), std::invalid_argument);
}

// Arcs: the plane word only when it changes, the two in-plane offsets always
// (4 decimals), the motion word again for the line after an arc.
TEST(GcodeWriter, ArcsNameTheirPlaneAndOffsets) {
  GcodeWriter w;
  w.feed(0.0, 0.0, -1.0, 500);
  EXPECT_TRUE(w.arc(18, true, 2.0, 0.0, -1.0, 1.0, 0.0, -0.00004, 500));
  EXPECT_TRUE(w.arc(18, true, 4.0, 0.0, -1.5, 1.23456, 0.0, 0.5, 500));
  EXPECT_TRUE(w.arc(19, false, 4.0, 1.0, -1.5, 0.0, 0.5, 0.25, 500));
  w.feed(4.0, 2.0, -1.5, 500);
  EXPECT_TRUE(w.arc(17, false, 5.0, 3.0, -1.5, 1.0, 0.0, 0.0, 500));
  EXPECT_FALSE(w.arc(17, false, 5.0, 3.0, -1.5, 1.0, 0.0, 0.0, 500));  // already there
  EXPECT_THROW(w.arc(20, false, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 500), std::invalid_argument);
  const std::vector<std::string> expect{"G1X0Y0Z-1F500", "G18G2X2I1K0",       "X4Z-1.5I1.2346K0.5",
                                        "G19G3Y1J0.5K0.25", "G1Y2", "G17G3X5Y3I1J0"};
  EXPECT_EQ(w.lines(), expect);
  EXPECT_EQ(w.motion_lines(), 6u);
}
