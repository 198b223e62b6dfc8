// The main command's feeds and speeds on a real controller: the cncsim
// program on its pty, with settings other than GRBL's defaults. The command
// connects first, reads $$, and computes the feeds within the controller's
// $30 and $110/$111; the operator's limits still win.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <regex>
#include <sstream>

#include "app_run.hpp"
#include "cncstream/geometry/stl.hpp"
#include "sim/pty_process.hpp"
#include "support/v_groove.hpp"

using namespace apptest;

namespace {

std::string v_groove_part() {
  const auto path = temp_dir() / "limits_v_groove.stl";
  if (!fs::exists(path)) cncstream::geometry::write_stl_binary(path, cncstream::test::v_groove());
  return path.string();
}

std::string read_text(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// The largest F or S word of a program (its comment lines left out).
double largest_word(const std::string& gcode, char letter) {
  const std::regex re(std::string(1, letter) + "([0-9.]+)");
  double most = 0;
  std::istringstream lines(gcode);
  for (std::string line; std::getline(lines, line);) {
    if (!line.empty() && line.front() == '(') continue;
    for (auto it = std::sregex_iterator(line.begin(), line.end(), re); it != std::sregex_iterator(); ++it)
      most = std::max(most, std::stod((*it)[1]));
  }
  return most;
}

}  // namespace

TEST(ControllerLimits, AnStlJobOnARealPortComputesItsFeedsWithinTheControllersSpindleAndRates) {
  const auto settings = temp_dir() / "limits_settings.txt";
  std::ofstream(settings) << "$30=12000\n$110=1200\n$111=1500\n$112=400\n";
  simtest::SimProcess sim({"--settings", settings.string()});
  const auto program = temp_dir() / "limits.nc";
  // A 6 mm flat of 3 flutes in maple wants about 21,000 rpm, more than $30, and at $30's 12,000 rpm
  // still more than $110's 1,200 mm/min: the feed is bound there and the rpm comes down with it, the
  // plan saying both. No --yes and no terminal: the plan is shown, the program written, nothing
  // streamed (exit 2).
  const std::vector<std::string> job{v_groove_part(), sim.slave(), "--tool", "flat:6", "--flutes", "3", "--material",
                                     "maple", "--stock", "none", "--stepover", "2", "--tolerance", "0.05", "-o",
                                     program.string()};
  const AppRun r = run_cncstream(job, 120);
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_TRUE(r.has("reading the controller's settings ($$)")) << r.out;
  EXPECT_TRUE(r.has("spindle max $30 = 12000")) << r.out;
  EXPECT_TRUE(r.has("max rate $110/$111 = 1200")) << r.out;
  const std::string gcode = read_text(program);
  ASSERT_FALSE(gcode.empty()) << r.out;
  EXPECT_GT(largest_word(gcode, 'S'), 0);
  EXPECT_LT(largest_word(gcode, 'S'), 12000);  // lowered with the feed
  EXPECT_EQ(largest_word(gcode, 'F'), 1200);

  // The operator's limits win over the controller's.
  std::vector<std::string> given = job;
  for (const char* a : {"--spindle-max", "10000", "--max-feed", "900"}) given.emplace_back(a);
  const AppRun g = run_cncstream(given, 120);
  EXPECT_EQ(g.code, 2) << g.out;
  EXPECT_TRUE(g.has("spindle max $30 = 10000")) << g.out;
  EXPECT_TRUE(g.has("max rate $110/$111 = 900")) << g.out;
  const std::string given_gcode = read_text(program);
  EXPECT_LT(largest_word(given_gcode, 'S'), 10000);
  EXPECT_EQ(largest_word(given_gcode, 'F'), 900);
  EXPECT_EQ(sim.stop(), 0) << sim.stderr_text();
}
