// The complete job of the plaque (and of a shared mesh, a gear) from its
// block: Z-level roughing with a flat, a tool change, finishing with a
// 3.175 mm ball, in one program, run line by line in the simulator with the
// job's tool table and the operator's cycle start at the pause: nothing
// below the design, no move deeper than its cutter's maximum depth, the
// finishing pass within its depth of the roughed surface, and the part
// finished.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <cstdint>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "cncsim/machine.hpp"
#include "cncsim/removal.hpp"
#include "cncstream/cam/deviation.hpp"
#include "cncstream/cam/height_field_io.hpp"
#include "cncstream/cam/zlevel_roughing.hpp"
#include "cncstream/gcode/program_pause.hpp"
#include "cncstream/jobs/toolpath_job.hpp"
#include "move_depth.hpp"
#include "sim_test_util.hpp"
#include "support/rs274.hpp"

using namespace cncstream;

namespace {

jobs::ToolpathParams plaque_job() {
  jobs::ToolpathParams p;
  p.part.stl = (std::filesystem::path(CNCSTREAM_SOURCE_DIR) / "examples/plaque.stl").string();
  p.cutter = cam::parse_cutter_spec("ball:3.175");
  p.stepover = 1.0;  // coarse: the test is about depths, not the finish
  p.tolerance = 0.01;
  p.feed = 3000;
  p.rpm = 0;
  p.stock = jobs::StockSpec{};  // auto: the part's box grown by 1 mm
  p.rough = cam::parse_cutter_spec("flat:6");
  return p;
}

struct Cut {
  cam::HeightFieldStock stock;
  // The largest depth one move took off, per operation (1, 2, ... in the
  // program's order; the machine runs dry at each operation's first line).
  simtest::MoveDepth depth;
  int pauses = 0;
};

// Runs `gcode` line by line from `start` with the job's tool table, the
// operator's cycle start at each pause; stops after `max_lines` lines.
// Moves' depths leave out slivers narrower than `tolerance` (the arcs').
Cut run(const jobs::ToolpathProgram& prog, cam::HeightFieldStock start, double tolerance, std::size_t max_lines = SIZE_MAX,
        double leave = 0.3) {
  cncsim::MachineOptions mo;
  mo.instant_waits = true;
  // Where the operator left it: above the stock (the machine's zero is the
  // part's top, inside a stock with a margin above it).
  mo.start_position = geometry::Vec3{0, 0, prog.stock->hi.z + 5};
  cncsim::Machine m(mo);
  cncsim::MaterialRemoval removal(std::move(start), prog.operations.front().cutter);
  cncsim::ToolTable tools;
  for (const auto& op : prog.operations) tools[op.tool] = op.cutter;
  Cut c{removal.stock(), {}, 0};
  c.depth.rim = std::max(0.01, tolerance);
  // The finishing cutter's side cut of the skin the roughing left beside a
  // wall is as tall as the wall, a leave wide (and the roughing's regions'
  // tolerance): not its depth of cut.
  if (prog.operations.size() > 1) {
    c.depth.rim_of[static_cast<int>(prog.operations.size())] = leave + cam::RoughingParams{}.tolerance + 0.01;
  }
  int op = 1;
  m.set_tool_observer([&](int t) { removal.set_cutter(tools.at(t)); });
  m.set_motion_observer([&](const geometry::Vec3& a, const geometry::Vec3& b, bool) { c.depth.cut(removal, op, removal.cutter(), a, b); });
  std::istringstream in(prog.gcode);
  std::string line;
  for (std::size_t n = 0; n < max_lines && std::getline(in, line); ++n) {
    if (static_cast<std::size_t>(op) < prog.operations.size() && n + 1 == prog.operations[op].first_line) {
      m.run_until_idle();  // the moves so far are the operation's before
      ++op;
    }
    const std::string out = simtest::send(m, line);
    EXPECT_EQ(out.find("error"), std::string::npos) << line << " -> " << out;
    if (gcode::is_program_pause(line)) {
      ++c.pauses;
      m.run_until_idle();
      m.receive("~");  // the operator changed the tool and pressed cycle start
    }
  }
  m.run_until_idle();
  c.stock = removal.stock();
  return c;
}

// The job's stock block, its nodes off round numbers (none on the part's
// silhouette).
cam::HeightFieldStock block_of(const jobs::ToolpathProgram& prog) {
  const geometry::Box3 s = *prog.stock;
  cam::GridSpec g = cam::GridSpec::covering(s.lo.x + 0.0373, s.lo.y + 0.0411, s.hi.x, s.hi.y, 0.25, 0.25);
  return cam::HeightFieldStock(g, s.hi.z);
}

void print_deepest(const Cut& c) {
  for (const auto& [t, ab] : c.depth.where)
    std::cout << "  operation " << t << " deepest " << c.depth.deepest.at(t) << " mm from " << ab.first.x << "," << ab.first.y
              << "," << ab.first.z << " to " << ab.second.x << "," << ab.second.y << "," << ab.second.z << " (node "
              << c.depth.node.at(t).x << "," << c.depth.node.at(t).y << " from " << c.depth.node.at(t).z << ")\n";
}

// Nothing of the machined stock below the design (beyond a micron).
void expect_no_gouge(const jobs::ToolpathProgram& prog, const cam::HeightFieldStock& stock) {
  const cam::DesignHeights design = cam::design_heights(prog.work_mesh, stock.grid());
  const cam::DeviationResult dev = cam::compare_to_design(stock, design, 0.01);
  EXPECT_FALSE(dev.stats.has_gouge && dev.stats.largest_gouge.value < -1e-3)
      << "gouge of " << dev.stats.largest_gouge.value << " at X" << dev.stats.largest_gouge.x << " Y"
      << dev.stats.largest_gouge.y;
}

// No move deeper than its operation may cut (beyond 1e-3 mm; the finishing
// beyond `finishing_slack`). The finishing's max_depth is what it was
// measured to cut; its limit is its cutter's.
void expect_moves_within_limits(const jobs::ToolpathProgram& prog, const Cut& c, double finishing_slack) {
  for (std::size_t k = 0; k < prog.operations.size(); ++k) {
    const jobs::OperationSummary& o = prog.operations[k];
    const bool finishing = o.name == "finishing";
    const double limit = finishing ? jobs::default_max_depth(o.cutter) : o.max_depth;
    const int op = static_cast<int>(k) + 1;
    ASSERT_TRUE(c.depth.deepest.count(op)) << o.name;
    std::cout << o.name << ": deepest cut of one move " << c.depth.deepest.at(op) << " mm (max " << limit << ")\n";
    EXPECT_LE(c.depth.deepest.at(op), limit + (finishing ? finishing_slack : 1e-3)) << o.name;
  }
}

// LinuxCNC's interpreter takes the whole program (the tool change's M0,
// the roughing's G17 arcs, the rows' G18 arcs) and makes the same moves of
// it as ours. (setup.sh installs it; skipped where it is missing.)
void expect_rs274_makes_our_moves(const std::string& gcode) {
  if (!test::rs274_available()) {
    std::cout << "rs274 (linuxcnc-uspace) is not installed: the program was not checked with it\n";
    return;
  }
  const auto r = test::run_rs274(gcode);
  EXPECT_EQ(r.status, 0) << r.output.substr(0, 2000);
  std::string error;
  const auto ours = test::our_moves(gcode, error);
  EXPECT_EQ(error, "");
  ASSERT_EQ(ours.size(), r.moves.size());
  for (std::size_t k = 0; k < ours.size(); ++k) {
    ASSERT_LT(norm(ours[k].to - r.moves[k].to), 1e-4) << k;
    ASSERT_EQ(ours[k].turn, r.moves[k].turn) << k;
  }
}

}  // namespace

TEST(CompleteJob, PlaqueRoughedThenFinishedWithoutGougeOrOverDeepPass) {
  const jobs::ToolpathProgram prog = jobs::generate_toolpath(plaque_job());
  // The flat cannot enter gaps 3.2-3.8 mm wide where the ball goes down
  // 2.8 mm: the ball rest-roughs them first, then finishes without a tool
  // change.
  ASSERT_EQ(prog.operations.size(), 3u);
  EXPECT_EQ(prog.operations[0].name, "roughing");
  EXPECT_EQ(prog.operations[0].cutter.spec(), "flat:6");
  EXPECT_EQ(prog.operations[1].name, "rest roughing");
  EXPECT_EQ(prog.operations[1].tool, 2);
  EXPECT_EQ(prog.operations[1].cutter.spec(), "ball:3.175");
  EXPECT_GT(prog.operations[1].lines, 100u);
  EXPECT_LE(prog.operations[1].max_depth, jobs::default_max_depth(prog.operations[1].cutter));
  EXPECT_EQ(prog.operations[2].name, "finishing");
  EXPECT_EQ(prog.operations[2].tool, 2);
  // The finishing depth measured at the tip against the roughed stock.
  EXPECT_LE(prog.operations[2].max_depth, jobs::default_max_depth(prog.operations[2].cutter) + 1e-9);
  ASSERT_TRUE(prog.stock);
  for (const auto& n : prog.notes) std::cout << n << "\n";
  for (const auto& o : prog.operations)
    std::cout << o.name << ": " << o.lines << " lines, " << o.feed_time_s / 60 << " min of feed\n";

  const Cut c = run(prog, block_of(prog), plaque_job().tolerance);
  EXPECT_EQ(c.pauses, 1);  // one tool change: none between the ball's two operations
  // No move deeper than its cutter may cut (a grid node's drop, nodes on the
  // cutter's rim left out: see move_depth.hpp, the finishing cutter's side
  // cuts of the skin the roughing left too; the grid's 0.25 mm adds nothing
  // to a depth). T2: the rest roughing's moves and the finishing's.
  const auto& deepest = c.depth.deepest;
  ASSERT_TRUE(deepest.count(1) && deepest.count(2) && deepest.count(3));
  const double ball_max = jobs::default_max_depth(prog.operations[2].cutter);
  std::cout << "deepest cut of one move: roughing " << deepest.at(1) << " mm (max " << prog.operations[0].max_depth
            << "), rest roughing " << deepest.at(2) << " mm (max " << prog.operations[1].max_depth << "), finishing "
            << deepest.at(3) << " mm (max " << ball_max << ")\n";
  print_deepest(c);
  EXPECT_LE(deepest.at(1), prog.operations[0].max_depth + 1e-3);
  EXPECT_LE(deepest.at(2), prog.operations[1].max_depth + 1e-3);  // its step-down, under the ball's
  EXPECT_LE(deepest.at(3), ball_max + 1e-3);
  EXPECT_GT(deepest.at(1), 0.5 * prog.operations[0].max_depth);  // the roughing did take full cuts
  EXPECT_GT(deepest.at(2), 0.5 * ball_max);  // so did the rest roughing
  expect_no_gouge(prog, c.stock);
  expect_rs274_makes_our_moves(prog.gcode);
}

// A shared mesh with vertical walls, a spur gear 41.7 mm across and 8 mm
// thick, from its block: Z-level roughing with a 3 mm flat, rest roughing
// where the flat cannot reach between the teeth, steep-and-shallow
// finishing (waterlines on the teeth's flanks), run in sequence in the
// simulator: no gouge, no move deeper than its cutter may cut.
TEST(CompleteJob, GearwheelRoughedThenFinishedWithoutGougeOrOverDeepPass) {
  jobs::ToolpathParams p = plaque_job();
  p.part.stl = std::string(CNCSTREAM_SHARED_MESHES) + "/gearwheel.bin.stl";
  p.rough = cam::parse_cutter_spec("flat:3");
  p.strategy = jobs::FinishStrategy::SteepShallow;  // the command's default
  const jobs::ToolpathProgram prog = jobs::generate_toolpath(p);
  std::vector<std::string> names;
  for (const auto& o : prog.operations) names.push_back(o.name);
  ASSERT_EQ(names, (std::vector<std::string>{"roughing", "rest roughing", "finishing"}));
  EXPECT_NE(prog.operations[2].detail.find("waterlines"), std::string::npos) << prog.operations[2].detail;
  for (const auto& n : prog.notes) std::cout << n << "\n";

  const Cut c = run(prog, block_of(prog), p.tolerance);
  EXPECT_EQ(c.pauses, 1);
  print_deepest(c);
  expect_moves_within_limits(prog, c, 1e-3);
  EXPECT_GT(c.depth.deepest.at(1), 0.5 * prog.operations[0].max_depth);  // the roughing did take full cuts
  expect_no_gouge(prog, c.stock);
  expect_rs274_makes_our_moves(prog.gcode);
}

// The README's main job with a tapered ball (issue 28): a flat roughs, the
// taper (0.5 mm tip radius, 5 degrees per side, 12.9 mm of flutes) rest-roughs
// where the flat does not fit, then finishes steep-and-shallow. Its flutes
// touch the plaque's 3 mm base rim from out at their reach with the tip
// 9.9 mm below the part: no pass goes below the part's bottom, no move
// deeper than its cutter may cut, no gouge.
TEST(CompleteJob, PlaqueRoughedWithAFlatThenFinishedWithATaperedBallWithoutGougeOrOverDeepPass) {
  jobs::ToolpathParams p = plaque_job();
  p.cutter = cam::parse_cutter_spec("taper:1:5:3.175");
  p.strategy = jobs::FinishStrategy::SteepShallow;  // the command's default
  const jobs::ToolpathProgram prog = jobs::generate_toolpath(p);
  for (const auto& n : prog.notes) std::cout << n << "\n";
  std::vector<std::string> names;
  for (const auto& o : prog.operations) names.push_back(o.name);
  ASSERT_EQ(names, (std::vector<std::string>{"roughing", "rest roughing", "finishing"}));
  EXPECT_EQ(prog.operations[1].cutter.spec(), "taper:1:5:3.175");
  EXPECT_EQ(prog.operations[1].tool, 2);
  EXPECT_EQ(prog.operations[2].tool, 2);
  ASSERT_TRUE(prog.stock);
  // The part's bottom in work coordinates: the lowest the tip goes.
  const double bottom = prog.work_mesh.bounds().lo.z;
  std::string error;
  double lowest = 1e9;
  for (const auto& mv : test::our_moves(prog.gcode, error)) lowest = std::min(lowest, mv.to.z);
  ASSERT_EQ(error, "");
  EXPECT_GE(lowest, bottom - 1e-6);

  const Cut c = run(prog, block_of(prog), p.tolerance);
  EXPECT_EQ(c.pauses, 1);
  print_deepest(c);
  // The plan measures the finishing's path against the stock the rest
  // roughing leaves, which brings it to exactly the limit; the program
  // follows that path within its tolerance (arcs, merged points): the
  // simulator measured 1.5935 mm against the 1.5875 mm limit at one move.
  expect_moves_within_limits(prog, c, p.tolerance);
  EXPECT_GT(c.depth.deepest.at(2), 0.5 * prog.operations[1].max_depth);  // the rest roughing took full cuts
  expect_no_gouge(prog, c.stock);
}

// A roughing interrupted half way, its result written as the simulator
// writes it, and the job run again from that height map: the second
// roughing cuts only what is left (fewer lines, levels only where material
// stands above them), no move deeper than the cutter may cut, no gouge, and
// as much removed as by one roughing run whole.
TEST(CompleteJob, PlaqueRoughedAgainFromAnInterruptedRoughingCutsOnlyWhatIsLeft) {
  jobs::ToolpathParams p = plaque_job();
  p.stepover = 3.0;  // the finishing is not run here
  p.tolerance = 0.05;
  const jobs::ToolpathProgram first = jobs::generate_toolpath(p);
  ASSERT_GE(first.operations.size(), 2u);
  const jobs::OperationSummary& r1 = first.operations[0];
  // Up to the line before the next operation's tool change: the whole roughing.
  const std::size_t whole = first.operations[1].first_line - 1;
  const Cut full = run(first, block_of(first), p.tolerance, whole);
  const Cut half = run(first, block_of(first), p.tolerance, r1.first_line + r1.lines / 2);

  const auto dir = std::filesystem::temp_directory_path() / ("cncstream_rough_again_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto map = dir / "half.f32";
  cam::write_height_field(map, half.stock.grid(), half.stock.heights());
  jobs::ToolpathParams again = p;
  again.stock = jobs::parse_stock_spec(map.string());
  const jobs::ToolpathProgram second = jobs::generate_toolpath(again);
  const cam::HeightFieldData read = cam::read_height_field(map);
  std::filesystem::remove_all(dir);
  ASSERT_GE(second.operations.size(), 2u);
  const jobs::OperationSummary& r2 = second.operations[0];
  ASSERT_EQ(r2.name, "roughing");
  for (const auto& n : second.notes) std::cout << n << "\n";
  std::cout << "roughing lines: whole " << r1.lines << ", again from the half-cut stock " << r2.lines
            << "; feed time " << r1.feed_time_s / 60 << " and " << r2.feed_time_s / 60 << " min\n";
  // Fewer lines, though not by as much as the time: the whole roughing's
  // lines are few since tiny loops are plunged, not ramped in laps.
  EXPECT_LT(r2.lines, r1.lines * 9 / 10);
  EXPECT_LT(r2.feed_time_s, r1.feed_time_s * 3 / 4);
  EXPECT_GT(r2.lines, r1.lines / 10);  // it did go on

  const Cut c = run(second, cncsim::stock_from_heights(read.grid, read.z), p.tolerance, second.operations[1].first_line - 1);
  ASSERT_TRUE(c.depth.deepest.count(1));
  print_deepest(c);
  EXPECT_LE(c.depth.deepest.at(1), r2.max_depth + 1e-3);
  expect_no_gouge(second, c.stock);
  // About as much left as after the whole roughing (its levels are planned
  // anew from the half-cut stock's highest point, so its terraces lie at
  // other heights: compared in volume, not node by node).
  double left = 0, left_whole = 0, start = 0;
  for (std::size_t n = 0; n < c.stock.heights().size(); ++n) {
    left += c.stock.heights()[n];
    left_whole += full.stock.heights()[n];
    start += first.stock->hi.z;
  }
  const double cell = c.stock.grid().dx * c.stock.grid().dy;
  std::cout << "removed by the whole roughing " << (start - left_whole) * cell << " mm^3, by half and again "
            << (start - left) * cell << " mm^3\n";
  EXPECT_LE(left - left_whole, 0.01 * (start - left_whole));
}
