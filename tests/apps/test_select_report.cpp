// `cncstream select` end to end: the report folder holds what the issue asks
// for (numbers as JSON and CSV, the maps as PNG, per-node data on request),
// and its numbers agree with each other.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

#include "app_run.hpp"
#include "cam/cl_test_meshes.hpp"
#include "cncstream/geometry/stl.hpp"

using namespace apptest;
using namespace cncstream;

TEST(SelectReport, WritesNumbersMapsAndPerNodeData) {
  // A dome on a plate: flat ground (radiused wins) and steep flanks (ball wins).
  const geometry::Mesh part = cl_test::dome_on_plate(30, 12);
  const fs::path dir = temp_dir() / "select";
  fs::create_directories(dir);
  geometry::write_stl_binary(dir / "dome.stl", part, "dome");
  const fs::path out = dir / "report";
  const auto r = run_cncstream({"select", (dir / "dome.stl").string(), "--tools", "ball:4,bull:4:1", "--stepover", "1",
                                "--step", "0.2", "--nodes-csv", "-o", out.string()});
  ASSERT_EQ(r.code, 0) << r.out;
  for (const char* f : {"selection.json", "table_4_1.csv", "slope_bins.csv", "nodes.csv", "choice_volume.png",
                        "choice_area.png", "choice_min_scallop.png", "scallop_ball_4.png", "scallop_bull_4_1.png"})
    EXPECT_TRUE(fs::exists(out / f)) << f << "\n" << r.out;

  std::ifstream jf(out / "selection.json");
  const auto j = nlohmann::json::parse(jf);
  // rc = rk = 1: the corrected d_base gives the thesis's switch slopes on a plane.
  EXPECT_NEAR(j["switch_deg"]["volume_plane"].get<double>(), 34.7, 0.1);
  EXPECT_NEAR(j["switch_deg"]["area_plane"].get<double>(), 21.8, 0.1);
  ASSERT_TRUE(j["switch_deg"]["volume_measured"].is_number()) << j.dump(2);
  // The dome meets the plate in a concave crease (60 degrees): a ring that
  // neither cutter reaches, split off from the scallops.
  for (const char* c : {"ball:4", "bull:4:1"}) {
    ASSERT_TRUE(j["unreachable"].contains(c)) << j.dump(2);
    const double un = j["unreachable"][c]["max_mm"].get<double>();
    EXPECT_GT(un, 0.05) << c;
    EXPECT_LT(un, 2.0) << c;
    EXPECT_LT(j["unreachable"][c]["share_above_min_pct"].get<double>(), 25.0) << c;
  }

  // nodes.csv: one row per CL point, the choice consistent with d and d_base.
  std::ifstream nf(out / "nodes.csv");
  std::string line;
  std::getline(nf, line);
  EXPECT_EQ(line, "x,y,z_ball,z_radiused,d,slope_deg,by_volume,by_area");
  const double d_base = j["d_base_mm"]["volume"].get<double>();
  std::size_t rows = 0, decided = 0, consistent = 0;
  while (std::getline(nf, line)) {
    ++rows;
    std::vector<std::string> c;
    std::stringstream s(line);
    for (std::string f; std::getline(s, f, ',');) c.push_back(f);
    if (c.size() < 7 || c[4].empty() || c[6].empty()) continue;
    ++decided;
    const double d = std::stod(c[4]);
    consistent += (c[6] == "radiused") == (d > d_base);
  }
  EXPECT_GT(rows, 1000u);
  EXPECT_GT(decided, rows / 4);
  // Printed with 5 decimals: only nodes within rounding of d_base may disagree.
  EXPECT_GE(double(consistent), 0.999 * double(decided));
  EXPECT_EQ(j["analysis_nodes_on_part"].get<std::size_t>() >= decided, true);
}
