// Sizes beyond reason are refused before work starts, naming the size and
// the likely cause.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/geometry/stl.hpp"
#include "cncstream/jobs/size_limits.hpp"
#include "cncstream/jobs/toolpath_job.hpp"

using namespace cncstream;

namespace {

geometry::Box3 box(double x, double y, double z) {
  geometry::Box3 b;
  b.lo = {0, 0, 0};
  b.hi = {x, y, z};
  return b;
}

std::string refusal(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return {};
}

}  // namespace

TEST(SizeLimits, APartKilometresLongIsRefusedWithItsLikelyUnit) {
  EXPECT_EQ(refusal([] { jobs::check_part_size(box(2900, 100, 10), "ok.stl"); }), "");
  const auto um = refusal([] { jobs::check_part_size(box(1.96e6, 8e5, 5e4), "plaque_um.stl"); });
  EXPECT_NE(um.find("plaque_um.stl"), std::string::npos) << um;
  EXPECT_NE(um.find("1960000.0 x 800000.0 x 50000.0 mm"), std::string::npos) << um;
  EXPECT_NE(um.find("--scale 0.0001 it would be 196.0 mm"), std::string::npos) << um;
  const auto big = refusal([] { jobs::check_part_size(box(4000, 10, 10), "big.stl"); });
  EXPECT_NE(big.find("--max-part-size"), std::string::npos) << big;
  EXPECT_NE(refusal([] { jobs::check_part_size(box(std::nan(""), 1, 1), "nan.stl"); }), "");
}

TEST(SizeLimits, AGridBeyondMemoryIsRefusedBeforeAllocation) {
  EXPECT_EQ(refusal([] { jobs::check_grid_memory(1000, 1000, 8, 0.1, "grid", 1 << 30); }), "");
  const auto e = refusal([] { jobs::check_grid_memory(1e6, 1e6, 4, 0.001, "the CL grid", 1 << 30); });
  EXPECT_NE(e.find("the CL grid"), std::string::npos) << e;
  EXPECT_NE(e.find("4000.0 GB"), std::string::npos) << e;
  EXPECT_GT(jobs::memory_budget_bytes(), std::size_t{1} << 20);
}

TEST(SizeLimits, AToolPathOnAHugePartIsRefusedAtOnce) {
  // The plaque scaled by 10,000 (an STL in the wrong unit): refused in the
  // load stage, in well under a second, not after minutes of work.
  jobs::ToolpathParams p;
  p.part.stl = CNCSTREAM_SOURCE_DIR "/examples/plaque.stl";
  p.part.scale = 10000;
  p.cutter = cam::parse_cutter_spec("ball:3.175");
  const auto t0 = std::chrono::steady_clock::now();
  const auto e = refusal([&] { (void)jobs::generate_toolpath(p); });
  EXPECT_NE(e.find("plaque.stl: the part is"), std::string::npos) << e;
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 30.0);
  // A fine step over a normal part that would not fit in memory: refused too.
  jobs::ToolpathParams q;
  q.part.stl = CNCSTREAM_SOURCE_DIR "/examples/plaque.stl";
  q.part.max_extent_mm = 1e9;
  q.part.scale = 100;
  q.cutter = cam::parse_cutter_spec("ball:3.175");
  q.stepover = 0.0001;
  q.step = 0.0001;
  EXPECT_NE(refusal([&] { (void)jobs::generate_toolpath(q); }).find("the tool path"), std::string::npos);
}

TEST(SizeLimits, UnitsWarningNamesTheLikelyUnits) {
  using jobs::units_warning;
  // A plaque drawn in metres (0.12 m), read as mm: --units m gives 120 mm.
  const std::string m = units_warning(box(0.12, 0.1, 0.02), geometry::LengthUnit::Millimetre, 3.175, "plaque.stl");
  EXPECT_NE(m.find("plaque.stl"), std::string::npos) << m;
  EXPECT_NE(m.find("--units m (120 mm)"), std::string::npos) << m;
  // A part drawn in inches (4.7 x 3.9 in): --units in; metres would make it 4.7 m, too large to suggest.
  const std::string in = units_warning(box(4.7, 3.9, 0.8), geometry::LengthUnit::Millimetre, 6, "sign.stl");
  EXPECT_NE(in.find("--units in (119 mm)"), std::string::npos) << in;
  EXPECT_EQ(in.find("--units m"), std::string::npos) << in;
  EXPECT_NE(in.find("smaller than the 6 mm cutter"), std::string::npos) << in;
  // Plausible parts: no warning.
  EXPECT_EQ(units_warning(box(120, 100, 20), geometry::LengthUnit::Millimetre, 3.175, "p"), "");
  EXPECT_EQ(units_warning(box(4.7, 3.9, 0.8), geometry::LengthUnit::Inch, 6, "p").find("--units in"), std::string::npos);
  EXPECT_EQ(units_warning(box(12, 12, 3), geometry::LengthUnit::Millimetre, 6, "p"), "");
}
