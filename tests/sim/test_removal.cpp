#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "cncsim/machine.hpp"
#include "cncsim/removal.hpp"
#include "cncstream/cam/height_field_io.hpp"
#include "sim_test_util.hpp"

using namespace cncsim;

TEST(Removal, MachineMotionCutsTheStock) {
  Machine m;
  MaterialRemoval removal(parse_stock_box("0,0,-5:10,10,0", 0.1), cncstream::Cutter::ball(2));
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
  MaterialRemoval removal(parse_stock_box("0,0,-5:6,4,0", 0.2), cncstream::Cutter::flat(1.5));
  removal.cut({1, 1, 1}, {1, 1, -2});
  removal.cut({1, 1, -2}, {5, 3, -1});
  const std::string path = "/tmp/cncsim_removal_" + std::to_string(::getpid()) + ".f32";
  removal.write_result(path);
  const auto field = cncstream::read_height_field(path);
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
