#include <gtest/gtest.h>

#include "cncstream/protocol/travel_check.hpp"

using cncstream::gcode::program_extent;
using cncstream::protocol::max_travel_from;
using cncstream::protocol::travel_refusal;

TEST(TravelCheck, TravelNeedsAllOfDollar130To132AndHoming) {
  EXPECT_FALSE(max_travel_from({}));
  EXPECT_FALSE(max_travel_from({{22, 1}, {130, 300}, {131, 200}}));
  EXPECT_FALSE(max_travel_from({{22, 1}, {130, 300}, {131, 200}, {132, 0}}));
  // Homing off ($22=0) or unknown: the travel is GRBL's default, not the machine's.
  EXPECT_FALSE(max_travel_from({{22, 0}, {130, 300}, {131, 200}, {132, 80}}));
  EXPECT_FALSE(max_travel_from({{130, 300}, {131, 200}, {132, 80}}));
  const auto t = max_travel_from({{22, 1}, {110, 500}, {130, 300}, {131, 200}, {132, 80}});
  ASSERT_TRUE(t);
  EXPECT_EQ(*t, (std::array<double, 3>{300, 200, 80}));
}

TEST(TravelCheck, AProgramThatFitsPasses) {
  const auto e = program_extent({"G90 G0 X0 Y0 Z5", "G1 X300 Y200 Z-75 F500"});
  EXPECT_FALSE(travel_refusal(e, {300, 200, 80}));
  EXPECT_FALSE(travel_refusal(program_extent({"G0 Z5"}), {300, 200, 80}));
}

TEST(TravelCheck, NamesTheAxisTheExtentTheTravelAndAnInchMixUp) {
  // 8 x 3 "units" taken as inches: 203.2 x 76.2 mm on a 100 x 100 mm machine.
  const auto e = program_extent({"G20 G90 G0 X0 Y0 Z0.1", "G1 X8 Y3 F10"});
  const auto why = travel_refusal(e, {100, 100, 50});
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("X: the program spans 203.2 mm (0 .. 203.2 as traced), the machine travels 100 mm ($130)"),
            std::string::npos) << *why;
  EXPECT_EQ(why->find("Y:"), std::string::npos) << *why;  // Y fits
  EXPECT_NE(why->find("25.4 times too large"), std::string::npos) << *why;
  EXPECT_NE(why->find("--units in"), std::string::npos) << *why;
  EXPECT_NE(why->find("nothing was sent"), std::string::npos) << *why;
}

TEST(TravelCheck, AThousandTimesTooLargeSaysMetres) {
  const auto e = program_extent({"G90 G0 X0 Y0", "G1 X150000 Y120000 F500"});
  const auto why = travel_refusal(e, {300, 200, 80});
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("X: the program spans 150000 mm"), std::string::npos) << *why;
  EXPECT_NE(why->find("Y: the program spans 120000 mm"), std::string::npos) << *why;
  EXPECT_NE(why->find("$131"), std::string::npos) << *why;
  EXPECT_NE(why->find("1000 times too large"), std::string::npos) << *why;
}

TEST(TravelCheck, ALittleTooLargeIsNoUnitMixUp) {
  // 500 mm on 300: divided by 25.4 it would fit, but under twice the travel
  // is a part too large, not a unit factor.
  const auto why = travel_refusal(program_extent({"G90 G0 X0 Y0", "G1 X500 F500"}), {300, 200, 80});
  ASSERT_TRUE(why);
  EXPECT_EQ(why->find("times too large"), std::string::npos) << *why;
  EXPECT_NE(why->find("larger than the machine can move"), std::string::npos) << *why;
}

TEST(TravelCheck, NoFactorFitsSaysFarLarger) {
  const auto why = travel_refusal(program_extent({"G90 G0 X0 Y0", "G1 X400000 F500"}), {300, 200, 80});
  ASSERT_TRUE(why);
  EXPECT_EQ(why->find("times too large"), std::string::npos) << *why;
  EXPECT_NE(why->find("far larger"), std::string::npos) << *why;
}
