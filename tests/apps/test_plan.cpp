// The combined plan's predicted residual matches what the simulator
// measures after machining the plan's files in sequence (first cutter, tool
// change, clean-up), within the simulation grid's resolution.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <sstream>

#include "app_run.hpp"
#include "cam/cl_test_meshes.hpp"
#include "cncsim/machine.hpp"
#include "cncsim/removal.hpp"
#include "cncstream/cam/deviation.hpp"
#include "cncstream/geometry/stl.hpp"

using namespace apptest;
using namespace cncstream;

namespace {

// Streams a G-code file into the in-process simulator, one line at a time,
// letting the virtual clock run until each line is answered.
void run_file(cncsim::Machine& m, const fs::path& file) {
  std::ifstream f(file);
  ASSERT_TRUE(f) << file;
  std::string line;
  std::size_t n = 0;
  while (std::getline(f, line)) {
    ++n;
    m.receive(line + "\n");
    std::string out;
    for (int guard = 0;; ++guard) {
      out += m.take_output();
      if (out.find("ok") != std::string::npos || out.find("error:") != std::string::npos) break;
      ASSERT_LT(guard, 100000) << file << " line " << n << " never answered";
      m.advance(5.0);
    }
    ASSERT_EQ(out.find("error:"), std::string::npos) << file << " line " << n << ": " << line << " -> " << out;
  }
  for (int k = 0; k < 10000; ++k) m.advance(5.0);  // run the planner out
}

// "<key>   H:MM:SS   X.XXXX mm ..." -> X.XXXX
double number_after(const std::string& text, const std::string& key) {
  const auto p = text.find(key);
  if (p == std::string::npos) return NAN;
  std::istringstream in(text.substr(p + key.size()));
  std::string time, unit;
  double v = NAN;
  in >> time >> v >> unit;
  return in && unit == "mm" && time.find(':') != std::string::npos ? v : NAN;
}

}  // namespace

TEST(Plan, PredictedResidualMatchesTheSimulatorAfterBothFiles) {
  // A dome on a plate: the radiused cutter removes more on the plate and the
  // dome's gentle top, the ball on its flanks.
  const geometry::Mesh part = cl_test::dome_on_plate(40, 16);
  const fs::path dir = temp_dir() / "plan";
  fs::create_directories(dir);
  const fs::path stl = dir / "dome.stl";
  geometry::write_stl_binary(stl, part, "dome");
  const auto r = run_cncstream({"plan", stl.string(), "--tools", "ball:6,bull:6:1.5", "--stepover", "1.5", "--step", "0.2",
                                "--scallop-tol", "0.05", "-o", (dir / "out").string()});
  ASSERT_EQ(r.code, 0) << r.out;
  const double predicted = number_after(r.out, "combined (bull:6:1.5 then ball:6 clean-up)");
  ASSERT_TRUE(std::isfinite(predicted)) << r.out;
  const fs::path f1 = dir / "out" / "dome-1-bull_6_1.5.nc", f2 = dir / "out" / "dome-2-ball_6.nc";
  ASSERT_TRUE(fs::exists(f1)) << r.out;
  ASSERT_TRUE(fs::exists(f2)) << r.out;

  // The design in work coordinates (XY origin at the part's minimum, Z0 on top).
  geometry::Mesh work = part;
  const geometry::Box3 b = part.bounds();
  work.translate({-b.lo.x, -b.lo.y, -b.hi.z});
  cncsim::MachineOptions mo;
  mo.instant_waits = true;
  cncsim::Machine m(mo);
  const double res = 0.1;
  // The files select T1 and T2; the simulator's tool table mounts the cutters.
  cncsim::MaterialRemoval removal(cncsim::stock_box_for(work, res), cam::parse_cutter_spec("flat:1"));
  removal.set_tool_table(cncsim::parse_tool_table("1=bull:6:1.5,2=ball:6"));
  removal.attach(m);
  m.take_output();
  run_file(m, f1);
  EXPECT_EQ(removal.cutter().spec(), "bull:6:1.5");
  run_file(m, f2);
  EXPECT_EQ(removal.cutter().spec(), "ball:6");
  EXPECT_TRUE(removal.unknown_tools().empty());

  const cam::DesignHeights design = cam::design_heights(work, removal.stock().grid());
  double measured = 0;
  for (std::size_t k = 0; k < design.z.size(); ++k)
    if (!design.off_part[k]) measured = std::max(measured, removal.stock().heights()[k] - design.z[k]);
  // The two grids sample the same surface at different nodes: the largest
  // residual agrees to what a grid step can hide on the steepest slope cut
  // (the flanks here are at most ~60 degrees: 0.2 mm x tan 60 ~ 0.35 mm is
  // the bound; in practice far closer).
  SCOPED_TRACE(r.out);
  EXPECT_GT(measured, 0.0);
  EXPECT_NEAR(predicted, measured, 0.05 + 0.1 * measured) << "predicted " << predicted << " measured " << measured;
  std::cout << "combined plan: predicted largest residual " << predicted << " mm, simulator " << measured << " mm\n";
}

TEST(Plan, StreamedFileCutsWithTheToolItSelects) {
  // A plate with a bump; one plan file streamed to PORT=sim with a tool table:
  // the file's T1 mounts the radiused cutter, and the cut is written out.
  const geometry::Mesh part = cl_test::terrain(0, 0, 20, 80, [](double x, double y) {
    const double r = std::hypot(x - 10, y - 10);
    return 2 + std::max(0.0, 3 - r / 2);
  });
  const fs::path dir = temp_dir() / "plan-stream";
  fs::create_directories(dir);
  geometry::write_stl_binary(dir / "bump.stl", part, "bump");
  const auto r = run_cncstream({"plan", (dir / "bump.stl").string(), "--tools", "ball:4,bull:4:1", "--stepover", "1",
                                "--step", "0.25", "-o", (dir / "out").string()});
  ASSERT_EQ(r.code, 0) << r.out;
  const fs::path f1 = dir / "out" / "bump-1-bull_4_1.nc";
  ASSERT_TRUE(fs::exists(f1)) << r.out;
  geometry::Mesh work = part;
  const geometry::Box3 b = part.bounds();
  work.translate({-b.lo.x, -b.lo.y, -b.hi.z});
  geometry::write_stl_binary(dir / "bump-work.stl", work, "bump");
  const fs::path result = dir / "cut.f32";
  const auto s = run_cncstream({f1.string(), "sim", "--yes", "--no-journal", "--sim-design", (dir / "bump-work.stl").string(),
                                "--sim-tool", "flat:1", "--sim-tool-table", "1=bull:4:1,2=ball:4", "--sim-result",
                                result.string()});
  ASSERT_EQ(s.code, 0) << s.out;
  EXPECT_TRUE(s.has("verify (4 mm bull-nose")) << s.out;  // the cutter in the spindle at the end: T1
  // Nothing below the design, or less than a tenth of a micron (the verify's two phrasings).
  EXPECT_TRUE(s.has("no gouge: the machined surface is nowhere below the design") || s.has("largest gouge 0.0000 mm"))
      << s.out;
  EXPECT_TRUE(fs::exists(result) && fs::exists(dir / "cut.stl")) << s.out;
  // Without a cut to simulate the flags are refused, with a reason.
  const auto refused = run_cncstream({f1.string(), "sim", "--yes", "--no-journal", "--sim-result", result.string()});
  EXPECT_NE(refused.code, 0);
  EXPECT_TRUE(refused.has("need a cut to simulate")) << refused.out;
}
