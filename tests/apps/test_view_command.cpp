// `cncstream view` end to end: a screenshot without a window (EGL, no X) of
// the plaque with a program placed by its header's work origin, and the
// errors a person meets first.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "app_run.hpp"
#include "cncstream/cam/deviation.hpp"
#include "cncstream/cam/height_field_io.hpp"
#include "cncstream/geometry/stl.hpp"
#include "cncstream/image/deviation_map.hpp"
#include "cncstream/image/image.hpp"

using namespace apptest;

namespace {

// Sets (or, with nullptr, unsets) an environment variable for the test's
// life (the child inherits it).
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* v = std::getenv(name)) saved_ = v;
    if (value) {
      ::setenv(name, value, 1);
    } else {
      ::unsetenv(name);
    }
  }
  ~ScopedEnv() {
    if (saved_) {
      ::setenv(name_, saved_->c_str(), 1);
    } else {
      ::unsetenv(name_);
    }
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  const char* name_;
  std::optional<std::string> saved_;
};

// Mesa's llvmpipe keeps blocks its JIT allocated to the end, which no leak
// suppression can name (the GL and viewer tests run without the leak check
// too): the rendering child runs without it.
constexpr const char* kRenderChildAsan = "detect_leaks=0:abort_on_error=1";

}  // namespace

TEST(ViewCommand, ScreenshotOfThePlaqueAndItsProgramWithoutAWindow) {
  const fs::path nc = temp_dir() / "view_rows.nc";
  {
    std::ofstream f(nc);
    f << "(work origin: XY at part minimum, Z0 at part top)\nG21 G90 G17\nG0 Z5\nG0 X10 Y10\nG1 Z-1 F300\n"
         "G1 X110 F1200\nG2 X110 Y30 I0 J10\nG1 X10\nG0 Z5\n";
  }
  const fs::path png = temp_dir() / "view_top.png";
  const ScopedEnv no_display("DISPLAY", nullptr);  // no X is needed
  const ScopedEnv asan("ASAN_OPTIONS", kRenderChildAsan);
  const auto r = run_cncstream({"view", plaque(), "--program", nc.string(), "--cutter", "ball:3.175", "--screenshot",
                                png.string(), "--view", "top", "--size", "160x120"});
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("placed on the part by its work origin: offset X 0.000 Y 0.000 Z 10.500")) << r.out;
  EXPECT_TRUE(r.has("segments (3 rapid), 1 arc, 1 operation")) << r.out;
  EXPECT_TRUE(r.has("screenshot")) << r.out;
  const cncstream::RgbImage img = cncstream::read_png(png);
  ASSERT_EQ(img.width(), 160);
  ASSERT_EQ(img.height(), 120);
  int drawn = 0;
  for (int y = 0; y < img.height(); ++y)
    for (int x = 0; x < img.width(); ++x) drawn += !(img.get(x, y) == cncstream::Rgb{245, 246, 248});
  EXPECT_GT(drawn, 160 * 120 / 3);  // the plaque fills the fitted view
}

TEST(ViewCommand, WithoutADisplayItSaysSoAndSuggestsAScreenshot) {
  const ScopedEnv no_display("DISPLAY", nullptr), no_wayland("WAYLAND_DISPLAY", nullptr);
  const auto r = run_cncstream({"view", plaque()});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("no display")) << r.out;
  EXPECT_TRUE(r.has("--screenshot OUT.png")) << r.out;
}

TEST(ViewCommand, BadInputIsAClearError) {
  auto r = run_cncstream({"view"});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("nothing to show")) << r.out;
  r = run_cncstream({"view", plaque(), "--at", "1,2,3"});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("--at places the cutter")) << r.out;
  r = run_cncstream({"view", "--cutter", "ball:6", "--at", "1,2", "--screenshot", (temp_dir() / "x.png").string()});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("expected X,Y,Z")) << r.out;
  r = run_cncstream({"view", plaque(), "--screenshot", (temp_dir() / "x.png").string(), "--size", "0x10"});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("WIDTHxHEIGHT")) << r.out;
}

TEST(ViewCommand, CutScreenshotCarriesTheDeviationMapsLegend) {
  // A clean cut of the plaque: its design heights on a 2 mm grid.
  const cncstream::Mesh plaque_mesh = cncstream::load_stl(plaque()).mesh;
  const cncstream::GridSpec g = cncstream::GridSpec::covering(0, 0, 120, 100, 2, 2);
  const cncstream::DesignHeights d = cncstream::design_heights(plaque_mesh, g);
  std::vector<double> z(g.size());
  for (std::size_t k = 0; k < g.size(); ++k) z[k] = d.off_part[k] ? plaque_mesh.bounds().lo.z : d.z[k];
  const fs::path cut = temp_dir() / "view_cut.f32";
  cncstream::write_height_field(cut, g, z);
  const fs::path png = temp_dir() / "view_cut.png";
  const ScopedEnv asan("ASAN_OPTIONS", kRenderChildAsan);
  const auto r = run_cncstream({"view", "--cut", cut.string(), "--design", plaque(), "--screenshot", png.string(),
                                "--view", "top", "--size", "1000x640"});
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("61 x 51 nodes")) << r.out;
  EXPECT_TRUE(r.has(", 0 gouged,")) << r.out;
  const cncstream::RgbImage img = cncstream::read_png(png);
  ASSERT_EQ(img.width(), 1000);
  // The legend's swatches, in the map's own colours, right of the view.
  bool gouge_swatch = false, excess_swatch = false;
  for (int y = 0; y < img.height(); ++y)
    for (int x = img.width() / 2; x < img.width(); ++x) {
      gouge_swatch = gouge_swatch || img.get(x, y) == cncstream::DeviationPalette::gouge(0.6);
      excess_swatch = excess_swatch || img.get(x, y) == cncstream::DeviationPalette::excess(0.6);
    }
  EXPECT_TRUE(gouge_swatch);
  EXPECT_TRUE(excess_swatch);
}
