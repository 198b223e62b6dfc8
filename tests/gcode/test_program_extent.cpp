#include <gtest/gtest.h>

#include "cncstream/gcode/program_extent.hpp"

using cncstream::gcode::program_extent;
using cncstream::gcode::ProgramExtent;

namespace {

void expect_axis(const ProgramExtent& e, int axis, double lo, double hi) {
  const auto& a = e.axes[static_cast<std::size_t>(axis)];
  ASSERT_TRUE(a.known) << "axis " << axis;
  EXPECT_NEAR(a.lo, lo, 1e-9) << "axis " << axis;
  EXPECT_NEAR(a.hi, hi, 1e-9) << "axis " << axis;
}

}  // namespace

TEST(ProgramExtent, SpansThePositionsMovedTo) {
  const auto e = program_extent({"(part)", "%", "$H", "G21 G90", "G0 Z5", "G0 X10 Y-20", "G1 Z-3 F300",
                                 "G1 X110 Y30 ; last", "G0 Z5", "M2"});
  expect_axis(e, 0, 10, 110);
  expect_axis(e, 1, -20, 30);
  expect_axis(e, 2, -3, 5);
  EXPECT_DOUBLE_EQ(e.axes[0].size(), 100);
}

TEST(ProgramExtent, TheUnknownStartDoesNotCount) {
  // X and Y are never set: where the tool starts is not the program's.
  const auto e = program_extent({"G90 G0 Z5", "G1 Z-1 F100"});
  EXPECT_FALSE(e.axes[0].known);
  EXPECT_FALSE(e.axes[1].known);
  expect_axis(e, 2, -1, 5);
  EXPECT_EQ(e.axes[0].size(), 0);
}

TEST(ProgramExtent, InchesAreMillimetres) {
  const auto e = program_extent({"G20 G90", "G0 X0 Y0 Z0", "G1 X4 Y2 F10"});
  expect_axis(e, 0, 0, 101.6);
  expect_axis(e, 1, 0, 50.8);
}

TEST(ProgramExtent, IncrementalMovesCountOnceTheAxisIsKnown) {
  const auto e = program_extent({"G91 G0 X50", "G90 G0 X0 Y0", "G91 G1 X30 F100", "G1 X30"});
  expect_axis(e, 0, 0, 60);  // the first G91 X50 starts from an unknown X
}

TEST(ProgramExtent, ArcsCountTheirBulge) {
  // A half circle of radius 10 from (0,0) to (20,0) through (10,10).
  const auto e = program_extent({"G90 G17 G0 X0 Y0", "G2 X20 Y0 I10 J0 F100"});
  expect_axis(e, 0, 0, 20);
  EXPECT_NEAR(e.axes[1].hi, 10, 0.01);
  EXPECT_NEAR(e.axes[1].lo, 0, 1e-9);
}

TEST(ProgramExtent, MachineCoordinateAndStoredTargetsAreLeftOut) {
  // The work spans X 0..100; G53 and G28 go to machine positions whose
  // distance from the work is unknown here.
  const auto e = program_extent({"G90 G0 X0 Y0 Z5", "G1 X100 F500", "G53 G0 Z-1", "G53 X-400", "G28",
                                 "G0 X50 Y0 Z5", "G1 X20"});
  expect_axis(e, 0, 0, 100);
  expect_axis(e, 2, 5, 5);
}

TEST(ProgramExtent, AProbeTargetIsASearchLimit) {
  const auto e = program_extent({"G90 G0 X0 Y0 Z5", "G38.2 Z-500 F50", "G0 Z10"});
  expect_axis(e, 2, 5, 10);
}

TEST(ProgramExtent, EachCoordinateSystemIsMeasuredOnItsOwn) {
  // G54 and G55 offsets differ by an unknown amount: the largest counts.
  const auto e = program_extent({"G54 G90 G0 X0 Y0", "G1 X80 F500", "G55 G0 X0 Y0", "G1 X30"});
  expect_axis(e, 0, 0, 80);
}

TEST(ProgramExtent, RejectedLinesAreSkipped) {
  const auto e = program_extent({"G90 G0 X0 Y0", "G1 X1000", "G1 X10 F100"});  // no feed yet: error:22
  expect_axis(e, 0, 0, 10);
}
