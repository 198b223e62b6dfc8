// The lines of the operator's machine actions, and the probe report parser.
#include <gtest/gtest.h>

#include "cncstream/protocol/machine_actions.hpp"

using namespace cncstream::protocol;

TEST(MachineActions, ZeroNamesEachAxisOnceAndRefusesOthers) {
  EXPECT_EQ(zero_axes_lines("xyz", ActionFamily::Grbl), std::vector<std::string>{"G10L20P0X0Y0Z0"});
  EXPECT_EQ(zero_axes_lines("ZZ", ActionFamily::Grbl), std::vector<std::string>{"G10L20P0Z0"});
  // Marlin's G10 is a retract: its work zero is G92.
  EXPECT_EQ(zero_axes_lines("XY", ActionFamily::Marlin), std::vector<std::string>{"G92X0Y0"});
  EXPECT_THROW(zero_axes_lines("XA", ActionFamily::Grbl), std::invalid_argument);
  EXPECT_THROW(zero_axes_lines("", ActionFamily::Grbl), std::invalid_argument);
}

TEST(MachineActions, SafeZNeverGoesDownAndWorkZeroGoesThereFirst) {
  MachineActionSettings s;
  s.safe_z_mm = 5;
  EXPECT_EQ(safe_z_lines(s, -2.0), std::vector<std::string>{"G21G90G0Z5.000"});
  EXPECT_TRUE(safe_z_lines(s, 12.0).empty());
  EXPECT_EQ(safe_z_lines(s, std::nullopt), std::vector<std::string>{"G21G90G0Z5.000"});
  EXPECT_EQ(go_to_work_zero_lines(s, -1.0),
            (std::vector<std::string>{"G21G90G0Z5.000", "G21G90G0X0Y0", "G0Z0"}));
  s.safe_z_machine_mm = -1;
  EXPECT_EQ(safe_z_lines(s, 50.0), std::vector<std::string>{"G21G53G0Z-1.000"});
}

TEST(MachineActions, SpindleAndProbeLines) {
  MachineActionSettings s;
  s.spindle_rpm = 12000;
  EXPECT_EQ(spindle_lines(true, s), std::vector<std::string>{"M3S12000"});
  EXPECT_EQ(spindle_lines(false, s), std::vector<std::string>{"M5"});
  s.probe_travel_mm = 25;
  s.probe_feed_mm_min = 80;
  s.probe_plate_mm = 9.8;
  s.probe_retract_mm = 3;
  EXPECT_EQ(probe_z_lines(s), (std::vector<std::string>{"G21G91G38.2Z-25.000F80", "G90"}));
  EXPECT_EQ(probe_finish_lines(s, -41.25),
            (std::vector<std::string>{"G21G53G1Z-41.250F80", "G10L20P0Z9.800", "G21G91G0Z3.000", "G90"}));
}

TEST(MachineActions, ProbeReportsParseStrictly) {
  auto r = parse_probe_report("[PRB:1.000,-2.500,-12.345:1]");
  ASSERT_TRUE(r);
  EXPECT_DOUBLE_EQ(r->z, -12.345);
  EXPECT_DOUBLE_EQ(r->y, -2.5);
  EXPECT_TRUE(r->touched);
  auto miss = parse_probe_report("[PRB:0.000,0.000,0.000,5.000:0]");  // a fourth axis
  ASSERT_TRUE(miss);
  EXPECT_FALSE(miss->touched);
  for (const char* bad : {"[PRB:1,2:1]", "[PRB:1,2,3:2]", "[PRB:1,2,3:1", "[PRB:a,2,3:1]", "[GC:G0 G54]",
                          "[PRB:1,2,3:1]x", "[PRB:1,2,nan:1]"})
    EXPECT_FALSE(parse_probe_report(bad)) << bad;
}
