// The LCD encoder against bytes worked out by hand from the layout.
#include <gtest/gtest.h>

#include <cmath>

#include "cncstream/pendant/whb04b_display.hpp"

using namespace cncstream::pendant;
using Bytes4 = std::array<std::uint8_t, 4>;

TEST(Whb04bDisplay, CoordinatesSignFractionAndRounding) {
  EXPECT_EQ(encode_coordinate(0.0), (Bytes4{0x00, 0x00, 0x00, 0x00}));
  EXPECT_EQ(encode_coordinate(-1.5), (Bytes4{0x01, 0x00, 0x88, 0x93}));       // 1, 5000 | sign
  EXPECT_EQ(encode_coordinate(12.3456), (Bytes4{0x0c, 0x00, 0x80, 0x0d}));    // 12, 3456
  EXPECT_EQ(encode_coordinate(123.45678), (Bytes4{0x7b, 0x00, 0xd8, 0x11}));  // 123, 4568 (rounded)
  EXPECT_EQ(encode_coordinate(-0.0001), (Bytes4{0x00, 0x00, 0x01, 0x80}));    // 0, 1 | sign
  EXPECT_EQ(encode_coordinate(-0.00004), (Bytes4{0x00, 0x00, 0x00, 0x00}));   // rounds to 0: no "-0.0000"
  EXPECT_EQ(encode_coordinate(300.99996), (Bytes4{0x2d, 0x01, 0x00, 0x00}));  // carries into the integer part
  EXPECT_EQ(encode_coordinate(70000), (Bytes4{0xff, 0xff, 0x0f, 0x27}));      // the largest shown: 65535.9999
  EXPECT_EQ(encode_coordinate(-70000), (Bytes4{0xff, 0xff, 0x0f, 0xa7}));
  EXPECT_EQ(encode_coordinate(std::nan("")), (Bytes4{0x00, 0x00, 0x00, 0x00}));
}

TEST(Whb04bDisplay, PayloadAndTheThreeFeatureReports) {
  DisplayState s;
  s.coordinates = {-1.5, 12.3456, 123.45678};
  s.work_coordinates = true;
  s.mode = DisplayMode::Step;
  s.reset = false;
  s.feed = 120;
  s.spindle = 90;
  const DisplayPayload expected{0xfe, 0xfd, 0xfe, 0x81, 0x01, 0x00, 0x88, 0x93, 0x0c, 0x00, 0x80,
                                0x0d, 0x7b, 0x00, 0xd8, 0x11, 0x78, 0x00, 0x5a, 0x00, 0x00};
  EXPECT_EQ(encode_display(s), expected);
  const auto reports = encode_display_reports(s);
  EXPECT_EQ(reports[0], (FeatureReport{0x06, 0xfe, 0xfd, 0xfe, 0x81, 0x01, 0x00, 0x88}));
  EXPECT_EQ(reports[1], (FeatureReport{0x06, 0x93, 0x0c, 0x00, 0x80, 0x0d, 0x7b, 0x00}));
  EXPECT_EQ(reports[2], (FeatureReport{0x06, 0xd8, 0x11, 0x78, 0x00, 0x5a, 0x00, 0x00}));
}

TEST(Whb04bDisplay, Flags) {
  DisplayState s;
  s.mode = DisplayMode::Continuous;
  s.work_coordinates = false;
  s.reset = true;
  EXPECT_EQ(encode_display(s)[3], 0x40);
  s.reset = false;
  EXPECT_EQ(encode_display(s)[3], 0x00);
  s.work_coordinates = true;
  EXPECT_EQ(encode_display(s)[3], 0x80);
  s.mode = DisplayMode::Percent;
  EXPECT_EQ(encode_display(s)[3], 0x83);
  s.mode = DisplayMode::Mpg;
  s.reset = true;
  EXPECT_EQ(encode_display(s)[3], 0xc2);
  // Overrides beyond 16 bits are shown as the largest.
  s.feed = 70000;
  const auto p = encode_display(s);
  EXPECT_EQ(p[16], 0xff);
  EXPECT_EQ(p[17], 0xff);
}
