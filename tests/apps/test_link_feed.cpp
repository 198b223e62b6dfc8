// A program is fitted to the link it will stream over, by default: the
// main command plans for its machine's wire (here the simulator's
// --sim-baud), `toolpath` for GRBL 1.1's 115,200 baud, and --link-rate
// replaces either ('usb': unbounded, F never lowered). Where a stretch of
// moves cannot arrive in time at its feed, F is lowered there and the plan
// says how much of the path runs below the commanded feed.
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "app_run.hpp"

using namespace apptest;

namespace {

// The F words of a program.
std::set<int> feeds(const fs::path& nc) {
  std::ifstream in(nc);
  std::stringstream s;
  s << in.rdbuf();
  const std::string text = s.str();
  std::set<int> out;
  const std::regex f("F([0-9]+)");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), f); it != std::sregex_iterator(); ++it)
    out.insert(std::stoi((*it)[1]));
  return out;
}

const std::vector<std::string> kCoarse = {"--tool", "ball:3.175", "--stepover", "3", "--stock", "none",
                                          "--strategy", "raster", "--feed", "3000", "--plunge-feed", "300"};

std::vector<std::string> args(std::vector<std::string> head, const std::vector<std::string>& tail) {
  head.insert(head.end(), tail.begin(), tail.end());
  return head;
}

}  // namespace

TEST(LinkFeed, TheMainCommandPlansForItsMachinesWire) {
  const fs::path nc = temp_dir() / "main-9600.nc";
  // No terminal and no --yes: the plan is printed, nothing is streamed.
  const auto r = run_cncstream(args({plaque(), "sim", "--sim-baud", "9600", "-o", nc.string()}, kCoarse));
  EXPECT_TRUE(r.has("not starting: no terminal to confirm on")) << r.out;
  EXPECT_TRUE(r.has("the link (960 bytes/s) cannot deliver the densest stretches at F3000")) << r.out;
  EXPECT_TRUE(std::regex_search(r.out, std::regex("the wire allows [0-9]+ mm/min here; [1-9][0-9.]* % of its path runs "
                                                  "below the commanded feed")))
      << r.out;
  const auto f = feeds(nc);
  EXPECT_TRUE(f.count(3000)) << "the commanded feed where the wire keeps up";
  EXPECT_LT(*f.begin(), 3000);
  for (int v : f) EXPECT_TRUE(v == 300 || v <= 3000) << v;
}

TEST(LinkFeed, ToolpathPlansForGrblsBaudAndLinkRateReplacesIt) {
  const fs::path def = temp_dir() / "default.nc", slow = temp_dir() / "slow.nc", usb = temp_dir() / "usb.nc";
  // 115,200 baud: the fitted rows arrive in time at F3000 everywhere.
  const auto d = run_cncstream(args({"toolpath", plaque(), "-o", def.string()}, kCoarse));
  ASSERT_EQ(d.code, 0) << d.out;
  EXPECT_TRUE(d.has("% of its path runs below the commanded feed")) << d.out;
  EXPECT_TRUE(d.has("; 0.0 % of its path runs below the commanded feed")) << d.out;
  EXPECT_EQ(feeds(def), (std::set<int>{300, 3000}));
  // 9,600 baud: F lowered in a few levels.
  const auto s = run_cncstream(args({"toolpath", plaque(), "--link-rate", "9600baud", "-o", slow.string()}, kCoarse));
  ASSERT_EQ(s.code, 0) << s.out;
  EXPECT_TRUE(s.has("F is lowered there")) << s.out;
  EXPECT_GT(feeds(slow).size(), 3u);
  // Unbounded: never lowered, and nothing said of the wire.
  const auto u = run_cncstream(args({"toolpath", plaque(), "--link-rate", "usb", "-o", usb.string()}, kCoarse));
  ASSERT_EQ(u.code, 0) << u.out;
  EXPECT_FALSE(u.has("F is lowered")) << u.out;
  EXPECT_EQ(feeds(usb), (std::set<int>{300, 3000}));
}
