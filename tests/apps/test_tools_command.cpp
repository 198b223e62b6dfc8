// `cncstream tools ...` and the library and feeds and speeds in a tool path
// job: the real program, a private library file.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "app_run.hpp"

using apptest::AppRun;
using apptest::run_cncstream;

namespace {

namespace fs = std::filesystem;

std::string read(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// A 20 x 20 x 5 mm pyramid: a part small enough to path in a moment.
std::string pyramid() {
  const fs::path p = apptest::temp_dir() / "pyramid.stl";
  std::ofstream o(p);
  const double a[4][3] = {{0, 0, 0}, {20, 0, 0}, {20, 20, 0}, {0, 20, 0}};
  const double top[3] = {10, 10, 5};
  o << "solid p\n";
  auto facet = [&](const double* x, const double* y, const double* z) {
    o << "facet normal 0 0 0\nouter loop\n";
    for (const double* v : {x, y, z}) o << "vertex " << v[0] << " " << v[1] << " " << v[2] << "\n";
    o << "endloop\nendfacet\n";
  };
  for (int k = 0; k < 4; ++k) facet(a[k], a[(k + 1) % 4], top);
  facet(a[0], a[2], a[1]);
  facet(a[0], a[3], a[2]);
  o << "endsolid p\n";
  return p.string();
}

}  // namespace

TEST(ToolsCommand, AddListShowImportRemove) {
  const fs::path lib = apptest::temp_dir() / "tools-crud.toml";
  fs::remove(lib);
  const std::string L = lib.string();
  AppRun r = run_cncstream({"tools", "--library", L, "add", "--name", "1/8 tapered ball", "--shape", "taper:1:5:3.175",
                            "--stick-out", "30", "--flute-length", "12"});
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("T1   1/8 tapered ball")) << r.out;
  r = run_cncstream({"tools", "--library", L, "add", "--name", "other", "--shape", "flat:6", "--number", "1"});
  EXPECT_EQ(r.code, 1);
  EXPECT_TRUE(r.has("tool number 1 is taken by '1/8 tapered ball'")) << r.out;
  r = run_cncstream({"tools", "--library", L, "add", "--name", "bad", "--shape", "taper:1:60"});
  EXPECT_EQ(r.code, 1);
  EXPECT_TRUE(r.has("angle per side 60")) << r.out;
  r = run_cncstream({"tools", "--library", L, "import",
                     (fs::path(CNCSTREAM_SOURCE_DIR) / "tests/fixtures/tools/tool.tbl").string()});
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("LinuxCNC tool table: 3 tools understood, 1 entry skipped")) << r.out;
  EXPECT_TRUE(r.has("skipped:    line 5 'probe' T99: no diameter (D)")) << r.out;
  r = run_cncstream({"tools", "--library", L, "list"});
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has(": 4 tools")) << r.out;
  r = run_cncstream({"tools", "--library", L, "show", "tapered"});
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("stick-out: 30 mm")) << r.out;
  r = run_cncstream({"tools", "--library", L, "remove", "ball nose"});
  ASSERT_EQ(r.code, 0) << r.out;
  r = run_cncstream({"tools", "--library", L, "show", "ball nose"});
  EXPECT_EQ(r.code, 1);
  EXPECT_TRUE(r.has("no tool named 'ball nose'")) << r.out;
  // A file someone broke: refused with its line.
  std::ofstream(lib, std::ios::app) << "[[tool]]\nnumber = 12\nname = \"x\"\nshape = \"vbit:60\"\n";
  r = run_cncstream({"tools", "--library", L, "list"});
  EXPECT_EQ(r.code, 1);
  EXPECT_TRUE(r.has(L + ":")) << r.out;
  EXPECT_TRUE(r.has("'vbit' takes")) << r.out;
}

TEST(ToolsCommand, ToolpathTakesALibraryToolAndAMaterial) {
  const fs::path lib = apptest::temp_dir() / "tools-job.toml";
  fs::remove(lib);
  ASSERT_EQ(run_cncstream({"tools", "--library", lib.string(), "add", "--name", "1/8 ball", "--shape", "ball:3.175",
                           "--number", "4"})
                .code,
            0);
  const std::string part = pyramid();
  const fs::path out = apptest::temp_dir() / "pyramid.nc";
  AppRun r = run_cncstream({"toolpath", part, "--tool-library", lib.string(), "--tool", "1/8 ball", "--material",
                            "walnut", "--stock", "none", "--stepover", "1", "-o", out.string(), "--progress", "never"});
  ASSERT_EQ(r.code, 0) << r.out;
  // ap = R: the whole 3.175 mm cuts; 450 m/min wants 45,115 rpm: the spindle's 24,000 binds. Chip load 0.1015 mm
  // (hardwood at 1/8 in), 1 mm of 3.175 engaged: x 3.175 / (2 sqrt(3.175 - 1)) = 1.0764; 24000 x 2 x 0.1015 x 1.0764.
  EXPECT_TRUE(r.has("T4 1/8 ball [ball:3.175]")) << r.out;
  EXPECT_TRUE(r.has("24000 rpm (spindle max $30 = 24000 (wanted 45115")) << r.out;
  EXPECT_TRUE(r.has("feed 5244 mm/min")) << r.out;
  EXPECT_TRUE(r.has("chip 0.1015 mm/tooth")) << r.out;
  const std::string g = read(out);
  EXPECT_NE(g.find("M3 S24000"), std::string::npos);
  EXPECT_NE(g.find("F5244"), std::string::npos);
  // The operator's feed and rpm win.
  r = run_cncstream({"toolpath", part, "--tool-library", lib.string(), "--tool", "4", "--material", "walnut", "--stock",
                     "none", "--stepover", "1", "--feed", "800", "--rpm", "16000", "-o", out.string(), "--progress",
                     "never"});
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("16000 rpm (given), feed 800 mm/min (given)")) << r.out;
  EXPECT_NE(read(out).find("F800"), std::string::npos);
  // Unknown names and materials list the candidates.
  r = run_cncstream({"toolpath", part, "--tool-library", lib.string(), "--tool", "3/8 ball", "-o", out.string()});
  EXPECT_EQ(r.code, 1);
  EXPECT_TRUE(r.has("no tool named '3/8 ball'")) << r.out;
  EXPECT_TRUE(r.has("T4 '1/8 ball' (ball:3.175)")) << r.out;
  r = run_cncstream({"toolpath", part, "--tool", "ball:3", "--material", "balsa", "-o", out.string()});
  EXPECT_EQ(r.code, 1);
  EXPECT_TRUE(r.has("unknown material 'balsa': known are hardwood")) << r.out;
}
