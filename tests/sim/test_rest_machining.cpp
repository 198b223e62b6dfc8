// Rest machining (`--rest`), known answer: a 90-degree V-groove finished
// with a 6 mm ball, whose tip stops 3 (sqrt 2 - 1) = 1.243 mm above the
// crease, then rest-machined with a 2 mm ball, which reaches down to
// 1 (sqrt 2 - 1) = 0.414 mm above it. The program runs in the simulator
// (tool change included) and the cut is measured against the design: the
// small ball cuts only along the groove, takes the crease down to its own
// reach, and nothing is gouged.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>

#include "cncsim/machine.hpp"
#include "cncsim/removal.hpp"
#include "cncstream/cam/deviation.hpp"
#include "cncstream/gcode/program_pause.hpp"
#include "cncstream/jobs/toolpath_job.hpp"
#include "sim_test_util.hpp"
#include "support/v_groove_job.hpp"

using namespace cncstream;

namespace {

struct Result {
  cam::HeightFieldStock stock;
  int pauses = 0;
};

// The program run in the simulator from a block at the part's top (work
// coordinates), each operation with its own cutter; up to `last_line`.
Result machine(const jobs::ToolpathProgram& prog, const cam::GridSpec& grid, std::size_t last_line = SIZE_MAX) {
  cncsim::MachineOptions mo;
  mo.instant_waits = true;
  cncsim::Machine m(mo);
  cncsim::MaterialRemoval removal(cam::HeightFieldStock(grid, 0), prog.operations.front().cutter);
  cncsim::ToolTable tools;
  for (const auto& op : prog.operations) tools[op.tool] = op.cutter;
  m.set_tool_observer([&](int t) { removal.set_cutter(tools.at(t)); });
  m.set_motion_observer([&](const geometry::Vec3& a, const geometry::Vec3& b, bool) { removal.cut(a, b); });
  Result r{removal.stock(), 0};
  std::istringstream in(prog.gcode);
  std::string line;
  for (std::size_t n = 1; n <= last_line && std::getline(in, line); ++n) {
    const std::string out = simtest::send(m, line);
    EXPECT_EQ(out.find("error"), std::string::npos) << line << " -> " << out;
    if (gcode::is_program_pause(line)) {
      ++r.pauses;
      m.run_until_idle();
      m.receive("~");
    }
  }
  m.run_until_idle();
  r.stock = removal.stock();
  return r;
}

}  // namespace

TEST(RestMachining, VGrooveCreaseComesDownFromTheBigBallsReachToTheSmallOnes) {
  jobs::ToolpathParams p = test::v_groove_job("ball:6", "ball:2");
  p.stepover = 0.5;
  p.tolerance = 0.01;
  p.rpm = 0;
  const jobs::ToolpathProgram prog = jobs::generate_toolpath(p);
  ASSERT_EQ(prog.operations.size(), 2u);
  EXPECT_EQ(prog.operations[0].name, "finishing");
  EXPECT_EQ(prog.operations[1].name, "rest machining");
  EXPECT_EQ(prog.operations[1].tool, 2);
  EXPECT_EQ(prog.operations[1].cutter.spec(), "ball:2");
  // Rows across the groove, then a pencil pass along its crease.
  std::printf("%s\n", prog.operations[1].detail.c_str());
  EXPECT_NE(prog.operations[1].detail.find(" pencil passes"), std::string::npos);
  EXPECT_EQ(prog.operations[1].detail.find(", 0 pencil passes"), std::string::npos);
  // It takes at most the difference of the two reaches at once.
  EXPECT_LE(prog.operations[1].max_depth, jobs::default_max_depth(prog.operations[1].cutter));

  // Work coordinates: X from the part's minimum, Z0 at its top.
  const cam::GridSpec grid = cam::GridSpec::covering(6.0131, 6.0173, 34, 14, 0.05, 0.25);
  const cam::DesignHeights design = cam::design_heights(prog.work_mesh, grid);
  const Result finished = machine(prog, grid, prog.operations[1].first_line - 1);
  const Result rested = machine(prog, grid);
  EXPECT_EQ(finished.pauses, 0);
  EXPECT_EQ(rested.pauses, 1);  // the tool change

  // Along the crease (x = 20): the big ball's reach, then the small one's.
  const double big = 3 * (std::sqrt(2.0) - 1), small = 1 * (std::sqrt(2.0) - 1);
  double crease_after_finish = 0, crease_after_rest = 0, gouge = 0, changed_far = 0;
  for (std::size_t j = 0; j < grid.ny; ++j)
    for (std::size_t i = 0; i < grid.nx; ++i) {
      const std::size_t k = j * grid.nx + i;
      const double x = grid.x(i);
      const double f = finished.stock.heights()[k] - design.z[k], r = rested.stock.heights()[k] - design.z[k];
      gouge = std::max(gouge, -r);
      if (std::fabs(x - 20) < 0.03) {
        crease_after_finish = std::max(crease_after_finish, f);
        crease_after_rest = std::max(crease_after_rest, r);
      }
      // Away from the groove the small ball cuts nothing.
      if (std::fabs(x - 20) > 4 + 1)
        changed_far = std::max(changed_far, finished.stock.heights()[k] - rested.stock.heights()[k]);
    }
  std::printf("crease: %.4f after the finishing, %.4f after the rest machining; deepest gouge %.5f; changed far %.5f\n", crease_after_finish, crease_after_rest, gouge, changed_far);
  EXPECT_NEAR(crease_after_finish, big, 0.03);
  EXPECT_NEAR(crease_after_rest, small, 0.03);
  EXPECT_LT(gouge, 2e-3);
  EXPECT_LT(changed_far, 1e-9);
}

TEST(RestMachining, RefusesARestCutterNotSmallerThanTheFinishingOne) {
  const jobs::ToolpathParams p = test::v_groove_job("ball:2", "ball:3");
  try {
    jobs::generate_toolpath(p);
    FAIL() << "a larger rest cutter was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("must be smaller than the finishing cutter"), std::string::npos) << e.what();
  }
}
