#include <gtest/gtest.h>

#include "cncstream/cam/cutter.hpp"

using namespace cncstream;

TEST(Cutter, Specs) {
  auto f = cam::parse_cutter_spec("flat:6");
  EXPECT_EQ(f.type, cam::CutterType::Flat);
  EXPECT_DOUBLE_EQ(f.radius, 3);
  EXPECT_DOUBLE_EQ(f.corner_radius, 0);
  auto b = cam::parse_cutter_spec("ball:3.175");
  EXPECT_EQ(b.type, cam::CutterType::Ball);
  EXPECT_DOUBLE_EQ(b.corner_radius, 3.175 / 2);
  auto bn = cam::parse_cutter_spec("bull:6:1");
  EXPECT_EQ(bn.type, cam::CutterType::Bull);
  EXPECT_DOUBLE_EQ(bn.core_radius(), 2);
  auto in = cam::parse_cutter_spec("ball:1/8in");
  EXPECT_DOUBLE_EQ(in.diameter(), 3.175);
  auto in2 = cam::parse_cutter_spec("bull:0.25in:0.03in");
  EXPECT_DOUBLE_EQ(in2.corner_radius, 0.03 * 25.4);
  EXPECT_EQ(cam::parse_cutter_spec(bn.spec()).corner_radius, 1);
}

TEST(Cutter, BadSpecsSayWhy) {
  for (const char* s : {"", "ball", "ball:", "ball:x", "cone:6", "bull:6", "bull:6:4", "flat:-1", "ball:1/0in",
                        "flat:6:1", "ball:nan"}) {
    SCOPED_TRACE(s);
    EXPECT_THROW(cam::parse_cutter_spec(s), cam::CutterSpecError);
  }
  try {
    cam::parse_cutter_spec("bull:6:4");
  } catch (const cam::CutterSpecError& e) {
    EXPECT_NE(std::string(e.what()).find("exceeds"), std::string::npos);
  }
}

TEST(Cutter, Profile) {
  const auto b = cam::Cutter::ball(10);
  EXPECT_DOUBLE_EQ(b.profile_height(0), 0);
  EXPECT_DOUBLE_EQ(b.profile_height(5), 5);
  EXPECT_NEAR(b.profile_height(3), 5 - 4, 1e-12);
  const auto f = cam::Cutter::flat(10);
  EXPECT_DOUBLE_EQ(f.profile_height(4.9), 0);
  const auto t = cam::Cutter::bull(10, 2);
  EXPECT_DOUBLE_EQ(t.profile_height(3), 0);
  EXPECT_DOUBLE_EQ(t.profile_height(5), 2);
}
