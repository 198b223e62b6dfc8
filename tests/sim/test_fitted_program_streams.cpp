// Issue 26's positive control: the plaque's default program, fitted in the
// band, streamed through the link-true simulator at a router's finishing feed.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

#include <fmt/core.h>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/gcode/link_feed_limit.hpp"
#include "cncstream/jobs/toolpath_job.hpp"
#include "support/streaming_check.hpp"

using namespace cncstream;

namespace {

// `cncstream toolpath examples/plaque.stl --tool ball:3.175 --feed 3000`:
// the CLI's defaults (steep-and-shallow from the part's block, tolerance
// 0.01 mm, arcs on).
jobs::ToolpathProgram plaque_default_at_f3000() {
  jobs::ToolpathParams p;
  p.part.stl = (std::filesystem::path(CNCSTREAM_SOURCE_DIR) / "examples/plaque.stl").string();
  p.cutter = cam::parse_cutter_spec("ball:3.175");
  p.strategy = jobs::FinishStrategy::SteepShallow;
  p.stock = jobs::StockSpec{};
  p.feed = 3000;
  return jobs::generate_toolpath(p);
}

}  // namespace

TEST(FittedProgramStreams, PlaqueDefaultAtF3000KeepsThePlannerFed) {
  const jobs::ToolpathProgram prog = plaque_default_at_f3000();
  EXPECT_EQ(prog.finish_pieces.empty(), false);
  const auto nc = std::filesystem::temp_directory_path() / fmt::format("plaque_fitted_{}.nc", ::getpid());
  {
    std::ofstream out(nc);
    out << prog.gcode;
  }
  const auto r = simtest::check_streaming(nc);
  std::filesystem::remove(nc);
  std::cout << r.describe() << "\n";
  // The wire: at most 5 % longer than on an unthrottled link over the
  // densest 20,000 lines (today's program, tests/fixtures, fails the check).
  EXPECT_LE(r.slowdown(), 1.05) << r.describe();
  EXPECT_TRUE(r.keeps_planner_fed()) << r.describe();

  // Lowering F is the exception: at 115,200 baud at most 1 % of the path
  // runs below its commanded feed.
  gcode::LinkFeedOptions lo;
  lo.link.bytes_per_second = gcode::bytes_per_second_for_baud(115200);
  const gcode::LinkFeedResult limited = gcode::limit_feed_to_link(prog.gcode, lo);
  std::cout << "below F on " << 100 * limited.share_below() << " % of " << limited.feed_length
            << " mm of feed moves; the worst window streams at " << limited.wire_feed << " mm/min\n";
  EXPECT_LE(limited.share_below(), 0.01);
}
