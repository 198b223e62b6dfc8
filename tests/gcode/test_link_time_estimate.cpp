// The time estimate over a serial link: a program whose moves are shorter
// than the wire delivers at their feed takes the wire's time.
#include <gtest/gtest.h>

#include <fmt/core.h>

#include <cmath>
#include <string>

#include "cncstream/gcode/program.hpp"

namespace {

using cncstream::gcode::MotionLimits;
using cncstream::gcode::StreamLink;

MotionLimits router() {
  MotionLimits l;
  l.max_rate = {6000, 6000, 6000};
  l.acceleration = {500, 500, 500};
  return l;
}

// `count` moves of `step` mm at F3000, each line `bytes` bytes with its newline.
std::string moves(std::size_t count, double step, std::size_t bytes) {
  std::string text = "G1F3000\n";
  for (std::size_t i = 1; i <= count; ++i) {
    std::string l = fmt::format("X{:.3f}Y{:.3f}", static_cast<double>(i) * step, (i % 2) * 0.001);
    while (l.size() + 1 < bytes) l.insert(l.begin() + 1, '0');
    text += l + "\n";
  }
  return text;
}

StreamLink serial_115200() {
  StreamLink link;
  link.bytes_per_second = cncstream::gcode::bytes_per_second_for_baud(115200);
  return link;
}

TEST(LinkTimeEstimate, DenseProgramTakesTheWiresTime) {
  const auto trace = cncstream::gcode::trace_program(moves(2000, 0.03, 25));
  const double wire = (2000 * 25 + 8) / 11520.0;  // 4.34 s
  const double on_link = estimate_program_time(trace, router(), serial_115200()).total();
  const double motion = estimate_program_time(trace, router()).total();
  const double at_feed = 2000 * 0.03 / 50.0;  // 1.2 s at F3000
  EXPECT_NEAR(on_link, wire, 0.03 * wire);
  // The motion alone (the planner always full) is held by the look-ahead
  // to sqrt(2 * 500 * 15 * 0.03) = 21.2 mm/s: 2.9 s, still flattering.
  EXPECT_NEAR(motion, 2000 * 0.03 / 21.2, 0.1 * motion);
  EXPECT_GT(on_link, 1.4 * motion);
  EXPECT_GT(on_link, 3.5 * at_feed);  // 25-byte lines of 0.03 mm: 3.6 times the time at F3000
}

TEST(LinkTimeEstimate, LongMovesTakeTheMotionsTime) {
  const auto trace = cncstream::gcode::trace_program(moves(300, 2.0, 25));
  const double on_link = estimate_program_time(trace, router(), serial_115200()).total();
  const double motion = estimate_program_time(trace, router()).total();
  EXPECT_NEAR(on_link, motion, 0.01 * motion);
}

TEST(LinkTimeEstimate, UnboundedLinkIsTheFullPlannerEstimate) {
  const auto trace = cncstream::gcode::trace_program(moves(500, 0.05, 20));
  EXPECT_DOUBLE_EQ(estimate_program_time(trace, router(), StreamLink{}).total(),
                   estimate_program_time(trace, router()).total());
}

TEST(LinkTimeEstimate, DeeperPlannerRunsShortMovesFaster) {
  const auto trace = cncstream::gcode::trace_program(moves(2000, 0.03, 16));
  StreamLink usb;  // native USB: the wire is not the limit
  usb.planner_blocks = 35;
  const double deep = estimate_program_time(trace, router(), usb).total();
  const double grbl = estimate_program_time(trace, router()).total();
  // sqrt(35 / 15) faster where the look-ahead binds.
  EXPECT_NEAR(grbl / deep, std::sqrt(35.0 / 15.0), 0.1);
}

TEST(LinkTimeEstimate, BlockRateBindsWhenSlowerThanTheWire) {
  const auto trace = cncstream::gcode::trace_program(moves(2000, 0.03, 16));
  StreamLink link = serial_115200();
  link.blocks_per_second = 300;
  EXPECT_NEAR(estimate_program_time(trace, router(), link).total(), 2000 / 300.0, 0.05 * 2000 / 300.0);
}

TEST(LinkTimeEstimate, LineEndTimesEndAtTheTotal) {
  const std::string text = moves(400, 0.03, 25);
  const auto trace = cncstream::gcode::trace_program(text);
  const auto ends = estimate_line_end_times(trace, router(), trace.lines, serial_115200());
  ASSERT_EQ(ends.size(), trace.lines);
  EXPECT_NEAR(ends.back(), estimate_program_time(trace, router(), serial_115200()).total(), 1e-9);
  for (std::size_t i = 1; i < ends.size(); ++i) EXPECT_GE(ends[i], ends[i - 1]);
}

}  // namespace
