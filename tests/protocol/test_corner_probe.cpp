// Corner probing (protocol/corner_probe.hpp) against the simulated GRBL 1.1
// with a stock block and a corner plate on its X-min/Y-min corner: the work
// offset it writes puts work zero on the block's corner, and it fails closed.
#include <gtest/gtest.h>

#include <cmath>
#include <fmt/core.h>

#include <functional>

#include "cncsim/machine.hpp"
#include "cncstream/protocol/corner_probe.hpp"
#include "cncstream/protocol/status_report.hpp"
#include "support/routine_bench.hpp"

using namespace cncstream;
using namespace cncstream::protocol;

namespace {

// The block's corner (machine mm), off round numbers; its top.
constexpr double kCornerX = 31.234, kCornerY = 18.766, kTopZ = -2.5;
constexpr double kThickness = 5, kLip = 3;

cncsim::MachineOptions corner_machine(bool plate = true, const std::string& tool = "flat:6") {
  cncsim::MachineOptions o;
  o.tool_shapes[0] = cam::parse_cutter_spec(tool);
  if (plate)
    o.probe_faces.push_back(cncsim::parse_corner_plate(fmt::format("{},{}", kThickness, kLip), kCornerX, kCornerY, kTopZ));
  return o;
}

CornerProbeConfig corner_config(CornerAxes axes = CornerAxes::XYZ, double radius = 3) {
  CornerProbeConfig c;
  c.axes = axes;
  c.plate = {kThickness, kLip, 50};
  c.tool_radius = radius;
  return c;
}

struct CornerBench : test::RoutineBench {
  double lowest_xy_travel_z = 1e9;  // the lowest tip on a rapid travel in XY (longer than a back-off)

  explicit CornerBench(cncsim::MachineOptions o = corner_machine(), const std::string& setup = "")
      : RoutineBench(std::move(o)) {
    command("G10 L2 P1 X1 Y2 Z3");
    if (!setup.empty()) command(setup);
    command("G53 G0 X45 Y40 Z" + std::to_string(kTopZ + kThickness + 10));  // over the plate, 10 mm above it
    m.set_motion_observer([this](const geometry::Vec3& a, const geometry::Vec3& b, bool rapid) {
      if (rapid && std::hypot(b.x - a.x, b.y - a.y) > 2.5)
        lowest_xy_travel_z = std::min(lowest_xy_travel_z, std::min(a.z, b.z));
    });
  }
  geometry::Vec3 g54() const { return m.parser().coords.wcs[0]; }
  // Where the block's corner (on its top) is in work coordinates now.
  geometry::Vec3 corner_in_work() const { return geometry::Vec3{kCornerX, kCornerY, kTopZ} - m.parser().wco(); }
};

}  // namespace

TEST(CornerProbe, FindsTheBlocksCornerWithin10Microns) {
  CornerBench b;
  CornerProbeRoutine r(corner_config());
  b.run(r);
  ASSERT_TRUE(r.succeeded()) << r.failure();
  const auto& res = r.result();
  ASSERT_TRUE(res.edge_x && res.edge_y && res.top_z);
  EXPECT_NEAR(*res.edge_x, kCornerX, 0.01);
  EXPECT_NEAR(*res.edge_y, kCornerY, 0.01);
  EXPECT_NEAR(*res.top_z, kTopZ, 0.01);
  EXPECT_TRUE(res.applied);
  // Work zero is the corner on the block's top.
  const geometry::Vec3 c = b.corner_in_work();
  EXPECT_NEAR(c.x, 0, 0.01);
  EXPECT_NEAR(c.y, 0, 0.01);
  EXPECT_NEAR(c.z, 0, 0.01);
  // Shown before written: the prompt came before the G10.
  ASSERT_EQ(b.prompts.size(), 1u);
  EXPECT_NE(b.prompts[0].find("G54"), std::string::npos);
  EXPECT_NE(b.prompts[0].find("was X1.000 Y2.000 Z3.000"), std::string::npos) << b.prompts[0];
  EXPECT_TRUE(b.sent_any("G10 L2 P1 X"));
  // Fast then slow on each axis, each bounded; the lowering beside the plate is a G38.3.
  EXPECT_TRUE(b.sent_any("G91 G38.2 Z-25.000 F150.000"));
  EXPECT_TRUE(b.sent_any("G38.2 X4.000 F20.000"));
  EXPECT_TRUE(b.sent_any("G38.2 Y4.000 F20.000"));
  EXPECT_TRUE(b.sent_any("G91 G38.3 Z-9.000"));
  // Every XY travel above the plate's top (the bit never dragged across it;
  // only the 2 mm back-offs from a wall run beside it).
  EXPECT_GT(b.lowest_xy_travel_z, kTopZ + kThickness + 1);
  EXPECT_TRUE(b.alarms.empty());
}

TEST(CornerProbe, AccountsForABallCuttersRadiusAndAnActiveG92) {
  CornerBench b(corner_machine(true, "ball:6.35"), "G92 X7 Y-3 Z1");
  CornerProbeRoutine r(corner_config(CornerAxes::XYZ, 3.175));
  b.run(r);
  ASSERT_TRUE(r.succeeded()) << r.failure();
  const geometry::Vec3 c = b.corner_in_work();
  EXPECT_NEAR(c.x, 0, 0.01);
  EXPECT_NEAR(c.y, 0, 0.01);
  EXPECT_NEAR(c.z, 0, 0.01);
}

TEST(CornerProbe, XyLeavesZAndZLeavesXy) {
  {
    CornerBench b;
    CornerProbeRoutine r(corner_config(CornerAxes::XY));
    b.run(r);
    ASSERT_TRUE(r.succeeded()) << r.failure();
    EXPECT_NEAR(b.corner_in_work().x, 0, 0.01);
    EXPECT_NEAR(b.corner_in_work().y, 0, 0.01);
    EXPECT_DOUBLE_EQ(b.g54().z, 3);
    EXPECT_FALSE(r.result().top_z);
  }
  {
    CornerBench b;
    CornerProbeRoutine r(corner_config(CornerAxes::Z));
    b.run(r);
    ASSERT_TRUE(r.succeeded()) << r.failure();
    EXPECT_NEAR(b.corner_in_work().z, 0, 0.01);
    EXPECT_DOUBLE_EQ(b.g54().x, 1);
    EXPECT_DOUBLE_EQ(b.g54().y, 2);
    EXPECT_FALSE(b.sent_any("X4.000"));
  }
}

TEST(CornerProbe, NoPlateAlarmsWithinTheTravelAndWritesNothing) {
  CornerBench b(corner_machine(false));
  CornerProbeRoutine r(corner_config());
  b.run(r);
  EXPECT_FALSE(r.succeeded());
  EXPECT_NE(b.alarms.find("ALARM:5"), std::string::npos);
  EXPECT_FALSE(b.sent_any("G10"));
  EXPECT_DOUBLE_EQ(b.g54().x, 1);
  EXPECT_DOUBLE_EQ(b.g54().z, 3);
}

TEST(CornerProbe, AnActiveInputIsRefusedBeforeAnyProbe) {
  CornerBench b;
  b.command("G53 G0 Z" + std::to_string(kTopZ + kThickness));  // the bit resting on the plate
  ASSERT_TRUE(b.m.probe_input());
  CornerProbeRoutine r(corner_config());
  b.run(r);
  EXPECT_FALSE(r.succeeded());
  EXPECT_NE(r.failure().find("active"), std::string::npos) << r.failure();
  EXPECT_FALSE(b.sent_any("G38"));
  EXPECT_TRUE(b.alarms.empty());
}

TEST(CornerProbe, AHoldOrADeclineOrALostLinkStopsItAndNothingIsWritten) {
  {
    CornerBench b;
    CornerProbeRoutine r(corner_config());
    bool held = false;
    b.run(r, 900, [&](double) {
      if (!held && b.sent_any("G38.2 X")) {
        b.m.receive("!");
        held = true;
      }
    });
    EXPECT_FALSE(r.succeeded());
    EXPECT_NE(r.failure().find("held"), std::string::npos) << r.failure();
    EXPECT_FALSE(b.sent_any("G10"));
    EXPECT_DOUBLE_EQ(b.g54().x, 1);
  }
  {
    CornerBench b;
    b.answer_yes = false;
    CornerProbeRoutine r(corner_config());
    b.run(r);
    EXPECT_FALSE(r.succeeded());
    EXPECT_EQ(b.prompts.size(), 1u);
    EXPECT_FALSE(b.sent_any("G10"));
    EXPECT_DOUBLE_EQ(b.g54().y, 2);
  }
  {
    CornerBench b;
    CornerProbeRoutine r(corner_config());
    std::size_t sent_at_loss = 0;
    b.run(r, 900, [&](double) {
      if (sent_at_loss == 0 && b.sent_any("G38.2 Y")) {
        r.abort("the controller disconnected");
        sent_at_loss = b.sent.size();
      }
    });
    EXPECT_FALSE(r.succeeded());
    EXPECT_EQ(b.sent.size(), sent_at_loss);  // nothing more once it ended
    EXPECT_FALSE(b.sent_any("G10"));
  }
}

TEST(CornerProbe, RefusesAConfigurationThatCannotWork) {
  CornerProbeConfig c = corner_config();
  c.plate.thickness = 0;
  EXPECT_THROW(CornerProbeRoutine{c}, std::invalid_argument);
  c = corner_config();
  c.plate.lip = 60;
  EXPECT_THROW(CornerProbeRoutine{c}, std::invalid_argument);
  EXPECT_EQ(parse_corner_axes("xy"), CornerAxes::XY);
  EXPECT_THROW(parse_corner_axes("xz"), std::invalid_argument);
}

TEST(CornerProbe, ParsesOffsetAndParserStateReports) {
  const auto o = parse_offset_report("[G55:1.000,-2.500,3.250]");
  ASSERT_TRUE(o);
  EXPECT_EQ(o->first, "G55");
  EXPECT_DOUBLE_EQ(o->second.y, -2.5);
  EXPECT_DOUBLE_EQ(parse_offset_report("[TLO:1.500]")->second.z, 1.5);
  EXPECT_FALSE(parse_offset_report("[PRB:0.000,0.000,0.000:1]"));
  EXPECT_FALSE(parse_offset_report("[G54:1.000,x,3.000]"));
  EXPECT_EQ(parse_active_coordinate_system("[GC:G0 G56 G17 G21 G90 G94 M5 M9 T0 F0 S0]"), 2);
  EXPECT_FALSE(parse_active_coordinate_system("[MSG:G54]"));
}
