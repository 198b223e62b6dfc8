// The roughing program run through the G-code interpreter and cut in the
// simulator's stock: the same pocket as the path, rapids through air only.
#include <gtest/gtest.h>

#include <cmath>
#include <variant>

#include "cam/zlevel_sim.hpp"
#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/stock.hpp"
#include "cncstream/gcode/arc_segments.hpp"
#include "cncstream/gcode/interpreter.hpp"
#include "cncstream/gcode/line_lexer.hpp"
#include "cncstream/gcode/roughing_program.hpp"

using namespace cncstream;

namespace {

struct PocketJob {
  geometry::Mesh mesh = zlevel_test::pocket_block();
  cam::Cutter cutter = cam::Cutter::flat(6);
  cam::ClEngine grown{mesh, cam::grown_cutter(cutter, 0.3)};
  cam::RoughingPath path;
  PocketJob() {
    cam::RoughingParams p;
    p.leave = 0.3;
    p.step_down = 3;
    p.tolerance = 0.02;
    path = cam::build_zlevel_roughing(grown, cutter, cam::StockBlock{-30, -25, 30, 25, 20}, p);
  }
};

}  // namespace

TEST(RoughingProgram, RunsInTheInterpreterAndCutsThePocket) {
  const PocketJob job;
  const geometry::Vec3 offset{30, 25, -20};  // work X0 Y0 at the block's corner, Z0 on its top
  MachiningParams mp;
  mp.feed = 1200;
  mp.plunge_feed = 300;
  mp.safe_z = 5;
  mp.tool = 2;
  mp.arcs = ArcFitOptions{};
  ProgramStats st;
  const std::string program = roughing_program(job.path, offset, mp, &st);
  EXPECT_NE(program.find("T2"), std::string::npos);
  EXPECT_NE(program.find("M3 S18000"), std::string::npos);
  EXPECT_NE(program.find("F300"), std::string::npos);  // the ramps
  EXPECT_NEAR(st.cut_length, job.path.stats.cut_length, 0.01 * job.path.stats.cut_length);
  EXPECT_LT(st.lines, 2000u);
  EXPECT_LE(st.work_bounds.hi.z, 0.5 + 1e-9);  // the ramps start half a millimetre above the top

  const cam::GridSpec g = cam::GridSpec::covering(-29.9627, -24.9589, 30, 25, 0.25, 0.25);
  cam::HeightFieldStock stock(g, 20);
  gcode::ParserState state;
  state.position = {0, 0, mp.safe_z};
  double deepest = 0, rapid_cut = 0;
  std::size_t moves = 0, arcs = 0;
  auto cut = [&](const geometry::Vec3& a, const geometry::Vec3& b, bool rapid) {
    stock.cut_segment(a - offset, b - offset, job.cutter);
    (rapid ? rapid_cut : deepest) = std::max(rapid ? rapid_cut : deepest, stock.last_max_depth());
    ++moves;
  };
  std::size_t line_no = 0;
  for (std::size_t at = 0; at < program.size();) {
    const std::size_t end = program.find('\n', at);
    const std::string raw = program.substr(at, end - at);
    at = end == std::string::npos ? program.size() : end + 1;
    ++line_no;
    const gcode::BlockResult r = gcode::execute_block(state, gcode::clean_line(raw).text);
    ASSERT_TRUE(r.ok()) << "line " << line_no << ": " << raw << " error " << r.status;
    state = r.state;
    for (const auto& act : r.actions) {
      if (const auto* m = std::get_if<gcode::LinearMove>(&act)) cut(m->from, m->to, m->rapid);
      if (const auto* a = std::get_if<gcode::ArcMove>(&act)) {
        ++arcs;
        geometry::Vec3 from = a->from;
        for (const geometry::Vec3& p : gcode::segment_arc(*a, 0.002)) {
          cut(from, p, false);
          from = p;
        }
      }
    }
  }
  EXPECT_GT(moves, 100u);
  EXPECT_LE(rapid_cut, 1e-9) << "a rapid cut material";
  EXPECT_LE(deepest, 3 + 0.002);  // Z is rounded up to the micron
  EXPECT_DOUBLE_EQ(state.position.z, mp.safe_z);
  for (std::size_t j = 0; j < g.ny; ++j)
    for (std::size_t i = 0; i < g.nx; ++i) {
      const double x = g.x(i), y = g.y(j), m = stock.at(i, j);
      const double in = std::min(15 - std::fabs(x), 10 - std::fabs(y));
      if (in < 0.3 - 0.02) {
        ASSERT_DOUBLE_EQ(m, 20.0) << x << "," << y;
        continue;
      }
      const double cx = std::max(0.0, std::fabs(x) - 11.7), cy = std::max(0.0, std::fabs(y) - 6.7);
      if (in > 0.3 + 0.02 && std::hypot(cx, cy) < 3 - 0.02) {
        ASSERT_NEAR(m, 10.3, 0.002) << x << "," << y;
      }
      ASSERT_GE(m, 10.3 - 1e-9);
    }
}

TEST(RoughingProgram, RejectsASafeZBelowTheClearanceAndBadFeeds) {
  const PocketJob job;
  const geometry::Vec3 offset{0, 0, -20};
  MachiningParams mp;
  mp.safe_z = 1;  // the clearance is 2 above the stock top
  EXPECT_THROW(roughing_program(job.path, offset, mp), std::invalid_argument);
  mp.safe_z = 5;
  EXPECT_NO_THROW(roughing_program(job.path, offset, mp));
  mp.plunge_feed = 0;
  EXPECT_THROW(roughing_program(job.path, offset, mp), std::invalid_argument);
  EXPECT_THROW(roughing_program(cam::RoughingPath{}, offset, MachiningParams{}), std::invalid_argument);
}
