#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "cncsim/machine.hpp"
#include "cncsim/removal.hpp"
#include "cncstream/cam/height_field_io.hpp"
#include "cncstream/geometry/mesh.hpp"
#include "cncstream/geometry/stl.hpp"
#include "sim_test_util.hpp"

using namespace cncsim;

TEST(Removal, MachineMotionCutsTheStock) {
  Machine m;
  MaterialRemoval removal(parse_stock_box("0,0,-5:10,10,0", 0.1), cncstream::cam::Cutter::ball(2));
  removal.attach(m);
  simtest::send(m, "G0 Z1");
  simtest::send(m, "G0 X2 Y5");
  simtest::send(m, "G1 Z-1 F200");
  simtest::send(m, "G1 X8");
  m.run_until_idle();
  const auto& s = removal.stock();
  EXPECT_NEAR(s.at(50, 50), -1, 1e-9);       // on the path: the ball's tip depth
  EXPECT_NEAR(s.at(50, 55), -1 + 1 - std::sqrt(1 - 0.25), 1e-9);  // 0.5 mm aside on the ball
  EXPECT_NEAR(s.at(50, 62), 0, 1e-12);       // beyond the 1 mm radius
  EXPECT_GT(s.removed_volume(), 0);
}

TEST(Removal, ResultFileRoundTripForVerify) {
  MaterialRemoval removal(parse_stock_box("0,0,-5:6,4,0", 0.2), cncstream::cam::Cutter::flat(1.5));
  removal.cut({1, 1, 1}, {1, 1, -2});
  removal.cut({1, 1, -2}, {5, 3, -1});
  const std::string path = "/tmp/cncsim_removal_" + std::to_string(::getpid()) + ".f32";
  const auto stl = removal.write_result(path);
  EXPECT_EQ(stl.extension(), ".stl");
  // The STL is the machined stock as a closed solid: top, walls, bottom.
  const auto solid = cncstream::geometry::summarize(cncstream::geometry::load_stl(stl).mesh);
  EXPECT_TRUE(solid.closed()) << solid.to_string();
  EXPECT_NEAR(solid.bounds.hi.z, 0, 1e-6);
  EXPECT_NEAR(solid.bounds.lo.z, -5, 1e-6);
  std::filesystem::remove(stl);
  const auto field = cncstream::cam::read_height_field(path);
  const auto rebuilt = stock_from_heights(field.grid, field.z);
  ASSERT_EQ(rebuilt.heights().size(), removal.stock().heights().size());
  for (std::size_t k = 0; k < rebuilt.heights().size(); ++k)
    EXPECT_NEAR(rebuilt.heights()[k], removal.stock().heights()[k], 1e-6) << k;  // float32 file
  std::filesystem::remove(path);
  std::filesystem::remove(path + ".txt");
}

TEST(Removal, BadStockTextIsNamed) {
  EXPECT_THROW(parse_stock_box("1,2,3", 0.1), std::invalid_argument);
  try {
    parse_stock_box("0,0,0:0,5,5", 0.1);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("0,0,0:0,5,5"), std::string::npos);
  }
}

TEST(Removal, ToolTableSwitchesTheCutterOnceTheQueuedMotionHasRun) {
  Machine m;
  MaterialRemoval removal(parse_stock_box("0,0,-5:10,10,0", 0.1), cncstream::cam::Cutter::ball(2));
  removal.set_tool_table(parse_tool_table("1=flat:2, 2=ball:2"));
  removal.attach(m);
  // T2 is parsed (and answered) while the T1 groove is still in the planner:
  // the swap waits for it, so that groove is cut flat.
  for (const char* l : {"T1", "G0 Z1", "G0 X2 Y3", "G1 Z-1 F200", "G1 X8", "T2", "G0 Z1", "G0 X2 Y7", "G1 Z-1",
                        "G1 X8", "T7", "G0 Z1"})
    EXPECT_NE(simtest::send(m, l).find("ok"), std::string::npos) << l;
  m.run_until_idle();
  const auto& s = removal.stock();
  EXPECT_NEAR(s.at(50, 30), -1, 1e-9);
  EXPECT_NEAR(s.at(50, 35), -1, 1e-9);  // 0.5 mm aside: still the flat bottom
  EXPECT_NEAR(s.at(50, 70), -1, 1e-9);
  EXPECT_NEAR(s.at(50, 75), -1 + 1 - std::sqrt(1 - 0.25), 1e-9);  // on the ball
  EXPECT_EQ(removal.unknown_tools(), std::set<int>{7});
}

TEST(Removal, ToolTableErrorsNameTheEntry) {
  const auto table = parse_tool_table("1=ball:3.175,2=bull:3.175:0.79");
  ASSERT_EQ(table.size(), 2u);
  EXPECT_EQ(table.at(2).type, cncstream::cam::CutterType::Bull);
  auto message = [](const std::string& text) {
    try {
      parse_tool_table(text);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("1=ball:3,x=flat:2").find("'x=flat:2'"), std::string::npos) << message("1=ball:3,x=flat:2");
  EXPECT_NE(message("3=cone:2").find("tool 3"), std::string::npos) << message("3=cone:2");
  EXPECT_NE(message(" , ").find("no tools"), std::string::npos);
  const std::string path = "/tmp/cncsim_tools_" + std::to_string(::getpid()) + ".txt";
  { std::ofstream(path) << "# shop tools\n1=flat:6\n\n2 = ball:1/8in  # finishing\n4=bull:6\n"; }
  const auto msg = message(path);
  EXPECT_NE(msg.find(path + " line 5"), std::string::npos) << msg;
  { std::ofstream(path) << "# shop tools\n1=flat:6\n\n2=ball:1/8in  # finishing\n"; }
  const auto from_file = parse_tool_table(path);
  EXPECT_NEAR(from_file.at(2).diameter(), 3.175, 1e-12);
  std::filesystem::remove(path);
}
