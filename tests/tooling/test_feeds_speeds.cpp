// Feeds and speeds: known answers worked by hand (the formulas in
// tooling/feeds_speeds.hpp), the shipped table's figures against its sources,
// and the machine's limits binding with the plan saying which.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "cncstream/tooling/feeds_speeds.hpp"

using namespace cncstream::tooling;

TEST(FeedsSpeeds, RpmFromSurfaceSpeed) {
  EXPECT_NEAR(rpm_for_surface_speed(100, 10), 3183.0989, 1e-3);
  EXPECT_NEAR(rpm_for_surface_speed(450, 6.35), 22557.3, 0.1);
}

TEST(FeedsSpeeds, ChipThinningBelowHalfTheDiameter) {
  // sqrt(6 * 0.6 - 0.36) = 1.8: 6 / 3.6
  EXPECT_NEAR(chip_thinning_factor(6, 0.6), 6.0 / 3.6, 1e-12);
  EXPECT_DOUBLE_EQ(chip_thinning_factor(6, 3), 1.0);
  EXPECT_DOUBLE_EQ(chip_thinning_factor(6, 4), 1.0);
  EXPECT_DOUBLE_EQ(chip_thinning_factor(6, 0), 1.0);
  // Continuous at ae = D/2 and growing as the engagement shrinks.
  EXPECT_NEAR(chip_thinning_factor(6, 2.999999), 1.0, 1e-6);
  EXPECT_GT(chip_thinning_factor(6, 0.1), chip_thinning_factor(6, 0.6));
}

TEST(FeedsSpeeds, EffectiveDiameterAtTheDepthOfCut) {
  EXPECT_DOUBLE_EQ(effective_diameter(parse_tool_spec("flat:6"), 0.5), 6);
  EXPECT_NEAR(effective_diameter(parse_tool_spec("ball:6"), 0.5), 2 * std::sqrt(2.75), 1e-12);
  EXPECT_DOUBLE_EQ(effective_diameter(parse_tool_spec("ball:6"), 3), 6);
  EXPECT_NEAR(effective_diameter(parse_tool_spec("bull:6:1"), 0.5), 2 * (2 + std::sqrt(0.75)), 1e-12);
  EXPECT_NEAR(effective_diameter(parse_tool_spec("vbit:90:12"), 2), 4, 1e-12);
  EXPECT_NEAR(effective_diameter(parse_tool_spec("vbit:90:12:0.2"), 2), 4.2, 1e-12);
  EXPECT_NEAR(effective_diameter(parse_tool_spec("vbit:60:12"), 2), 4 * std::tan(std::numbers::pi / 6), 1e-12);
  EXPECT_DOUBLE_EQ(effective_diameter(parse_tool_spec("vbit:90:12"), 10), 12);
  // Tapered ball, r 0.5, 5 deg per side: on the ball below r (1 - sin 5) = 0.45642, on the cone above.
  const auto taper = parse_tool_spec("taper:1:5:3.175");
  EXPECT_NEAR(effective_diameter(taper, 0.2), 0.8, 1e-12);
  const double a = 5 * std::numbers::pi / 180;
  EXPECT_NEAR(effective_diameter(taper, 1.0), 2 * (0.5 * std::cos(a) + (1 - 0.5 * (1 - std::sin(a))) * std::tan(a)), 1e-12);
  EXPECT_NEAR(effective_diameter(taper, 1.0), 1.091308, 1e-6);
  // Continuous where the ball meets the cone.
  const double h = 0.5 * (1 - std::sin(a));
  EXPECT_NEAR(effective_diameter(taper, h - 1e-9), effective_diameter(taper, h + 1e-9), 1e-6);
  EXPECT_DOUBLE_EQ(effective_diameter(taper, 100), 3.175);
}

TEST(FeedsSpeeds, MaterialTableCarriesTheChartsFigures) {
  const auto& t = builtin_materials();
  for (const char* m : {"hardwood", "softwood", "mdf", "plywood", "acrylic", "hdpe", "aluminium", "brass"})
    EXPECT_NO_THROW(t.find(m)) << m;
  const Material& hw = t.find("Walnut");  // an alias, any case
  EXPECT_EQ(hw.name, "hardwood");
  EXPECT_EQ(&t.find("maple"), &hw);
  // 1/4 in hardwood .009-.011 in [CS]: the middle, 0.01 in.
  EXPECT_NEAR(hw.chip_load_at(6.35), 0.254, 1e-9);
  // Between rows linearly; below the smallest in proportion; above the largest held.
  EXPECT_NEAR(hw.chip_load_at(4.7625), (0.1015 + 0.254) / 2, 1e-9);
  EXPECT_NEAR(hw.chip_load_at(1.5875), 0.1015 / 2, 1e-9);
  EXPECT_NEAR(hw.chip_load_at(25), 0.508, 1e-9);
  EXPECT_NEAR(hw.chip_load_at(6.35, true), 0.229, 1e-9);
  EXPECT_EQ(t.find("aluminum").name, "aluminium");
  try {
    t.find("unobtainium");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("hardwood (walnut"), std::string::npos) << e.what();
  }
}

TEST(FeedsSpeeds, MalformedMaterialTableIsRefusedWithItsLine) {
  try {
    parse_material_table("[[material]]\nname = \"x\"\nsurface_speed = [300, 200]\nchip_load = [[3, 0.1, 0.2]]\n", "m.toml");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("m.toml:3"), std::string::npos) << e.what();
  }
  try {
    parse_material_table("[[material]]\nname = \"x\"\nsurface_speed = [200, 300]\nchip_load = [[6, 0.1, 0.2], [3, 0.1, 0.2]]\n",
                         "m.toml");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("ascending"), std::string::npos) << e.what();
  }
}

TEST(FeedsSpeeds, SlotWithAFlatInHardwoodUnbounded) {
  CutRequest q;
  q.geometry = parse_tool_spec("flat:6.35");
  q.flutes = 2;
  q.material = &builtin_materials().find("walnut");
  q.depth_of_cut = 3;
  const Feeds f = compute_feeds(q);
  const double rpm = 1000 * 450 / (std::numbers::pi * 6.35);
  EXPECT_NEAR(f.rpm, rpm, 1e-6);
  EXPECT_NEAR(f.feed, rpm * 2 * 0.254, 1e-6);
  EXPECT_NEAR(f.chip_load, 0.254, 1e-12);
  EXPECT_NEAR(f.removal_rate, 3 * 6.35 * f.feed, 1e-6);
  EXPECT_DOUBLE_EQ(f.thinning, 1);
  EXPECT_NE(f.rpm_from.find("surface speed 450"), std::string::npos) << f.rpm_from;
  EXPECT_TRUE(f.warnings.empty());
}

TEST(FeedsSpeeds, MachineLimitsBindAndSayWhich) {
  CutRequest q;
  q.geometry = parse_tool_spec("flat:6.35");
  q.flutes = 2;
  q.material = &builtin_materials().find("hardwood");
  q.depth_of_cut = 3;
  q.limits.spindle_max = 18000;
  q.limits.max_feed_xy = 5000;
  q.limits.max_feed_z = 500;
  q.limits.spindle_min = 6000;
  const Feeds f = compute_feeds(q);
  // 22557 rpm wanted: $30 binds at 18000; then 18000 x 2 x 0.254 = 9144 mm/min wanted: $110 binds at 5000,
  // and the rpm comes down with it so that the chip keeps 0.254 mm: 5000 / (2 x 0.254) = 9843.
  EXPECT_NEAR(f.rpm, 5000 / (2 * 0.254), 1e-9);
  EXPECT_EQ(f.rpm_from, "lowered from 18000 (spindle max $30 = 18000) with the feed to keep the chip") << f.rpm_from;
  EXPECT_DOUBLE_EQ(f.feed, 5000);
  EXPECT_EQ(f.feed_from.rfind("max rate $110/$111 = 5000 (wanted 9144", 0), 0u) << f.feed_from;
  EXPECT_NEAR(f.chip_load, 0.254, 1e-12);
  EXPECT_DOUBLE_EQ(f.plunge_feed, 500);
  EXPECT_NEAR(f.removal_rate, 3 * 6.35 * 5000, 1e-9);
  EXPECT_TRUE(f.warnings.empty());
  // Only the spindle's rpm, with the operator's rpm kept: the chip thins.
  CutRequest fixed = q;
  fixed.rpm = 18000;
  EXPECT_NEAR(compute_feeds(fixed).chip_load, 5000.0 / 36000, 1e-12);
  // Down to $31 at most: then the chip thins.
  CutRequest slow = q;
  slow.limits.max_feed_xy = 1000;
  const Feeds s = compute_feeds(slow);
  EXPECT_DOUBLE_EQ(s.rpm, 6000);
  EXPECT_EQ(s.rpm_from, "lowered from 18000 (spindle max $30 = 18000) with the feed to keep the chip, to spindle min "
                        "$31 = 6000");
  EXPECT_NEAR(s.chip_load, 1000.0 / 12000, 1e-12);
  // The spindle's minimum binds a large tool in a slow material.
  CutRequest big = q;
  big.geometry = parse_tool_spec("flat:25");
  big.material = &builtin_materials().find("brass");
  big.limits.spindle_min = 8000;
  const Feeds b = compute_feeds(big);
  EXPECT_DOUBLE_EQ(b.rpm, 8000);  // 1000 x 225 / (pi x 25) = 2865 wanted
  EXPECT_EQ(b.rpm_from.rfind("spindle min $31 = 8000", 0), 0u) << b.rpm_from;
}

TEST(FeedsSpeeds, ChipThinningRaisesTheFeedAndKeepsTheChip) {
  CutRequest q;
  q.geometry = parse_tool_spec("flat:6.35");
  q.flutes = 2;
  q.material = &builtin_materials().find("mdf");
  q.depth_of_cut = 2;
  q.radial_engagement = 0.635;  // 10 %: factor 6.35 / (2 sqrt(3.629025)) = 1.6667
  const Feeds f = compute_feeds(q);
  EXPECT_NEAR(f.thinning, 6.35 / (2 * std::sqrt(6.35 * 0.635 - 0.635 * 0.635)), 1e-12);
  EXPECT_NEAR(f.thinning, 1.6667, 1e-4);
  EXPECT_NEAR(f.feed_per_tooth, 0.368 * f.thinning, 1e-9);
  EXPECT_NEAR(f.chip_load, 0.368, 1e-9);  // MDF at 1/4 in: .013-.016 in, the middle
}

TEST(FeedsSpeeds, TaperedBallUsesItsEffectiveDiameter) {
  // The README's main job: taper:1:5:3.175 in maple, finishing 0.3 mm deep at a 0.4 mm stepover.
  CutRequest q;
  q.geometry = parse_tool_spec("taper:1:5:3.175");
  q.flutes = 2;
  q.material = &builtin_materials().find("maple");
  q.depth_of_cut = 0.3;
  q.radial_engagement = 0.4;
  q.limits.spindle_max = 24000;
  const Feeds f = compute_feeds(q);
  const double d = 2 * std::sqrt(0.3 * 0.7);
  EXPECT_NEAR(f.effective_diameter, d, 1e-12);
  EXPECT_DOUBLE_EQ(f.rpm, 24000);  // 1000 x 450 / (pi x 0.917) = 156,000 wanted
  const double cl = 0.1015 * d / 3.175;
  const double thin = d / (2 * std::sqrt(d * 0.4 - 0.16));
  EXPECT_NEAR(f.feed, 24000 * 2 * cl * thin, 1e-6);
  EXPECT_NEAR(f.chip_load, cl, 1e-12);
}

TEST(FeedsSpeeds, OperatorAndToolDataWin) {
  CutRequest q;
  q.geometry = parse_tool_spec("ball:3.175");
  q.flutes = 2;
  q.material = &builtin_materials().find("walnut");
  q.rpm = 12000;
  q.feed = 900;
  q.limits.spindle_max = 10000;
  q.limits.max_feed_xy = 500;
  const Feeds f = compute_feeds(q);
  EXPECT_DOUBLE_EQ(f.rpm, 12000);
  EXPECT_DOUBLE_EQ(f.feed, 900);
  EXPECT_EQ(f.rpm_from, "given");
  EXPECT_NEAR(f.feed_per_tooth, 900.0 / 24000, 1e-12);
  // The tool's data for the material, over the table.
  CuttingData data;
  data.material = "walnut";
  data.rpm = 16000;
  data.chip_load = 0.05;
  CutRequest t;
  t.geometry = parse_tool_spec("flat:3.175");
  t.flutes = 2;
  t.material = q.material;
  t.tool_data = &data;
  const Feeds g = compute_feeds(t);
  EXPECT_DOUBLE_EQ(g.rpm, 16000);
  EXPECT_NEAR(g.feed, 16000 * 2 * 0.05, 1e-9);
  // No material and no data: an error that says what is missing.
  CutRequest none;
  none.geometry = t.geometry;
  EXPECT_THROW(compute_feeds(none), std::invalid_argument);
}

TEST(FeedsSpeeds, ARubbingChipIsWarned) {
  CutRequest q;
  q.geometry = parse_tool_spec("flat:6.35");
  q.flutes = 2;
  q.material = &builtin_materials().find("oak");
  q.depth_of_cut = 3;
  q.limits.max_feed_xy = 1000;  // 22557 rpm x 2 flutes: 0.022 mm a tooth
  q.rpm = 22557;                // the operator's: it stays
  const Feeds f = compute_feeds(q);
  ASSERT_EQ(f.warnings.size(), 1u);
  EXPECT_NE(f.warnings[0].find("rubs"), std::string::npos) << f.warnings[0];
  EXPECT_NE(f.warnings[0].find("burns wood"), std::string::npos) << f.warnings[0];
}
