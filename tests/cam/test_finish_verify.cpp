// End to end on the example plaque: CL engine -> raster path -> material
// removal (computed independently of the CL engine) -> comparison with the
// design surface. A gouge-free path leaves the machined surface nowhere
// below the design.
#include <gtest/gtest.h>

#include <filesystem>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/deviation.hpp"
#include "cncstream/cam/raster.hpp"
#include "cncstream/cam/stock.hpp"
#include "cncstream/geometry/stl.hpp"

using namespace cncstream;

class PlaqueFinish : public ::testing::TestWithParam<const char*> {};

TEST_P(PlaqueFinish, MachinedSurfaceHasNoGouge) {
  const auto part = geometry::load_stl(std::filesystem::path(CNCSTREAM_SOURCE_DIR) / "examples/plaque.stl");
  const cam::Cutter cutter = cam::parse_cutter_spec(GetParam());
  const cam::ClEngine engine(part.mesh, cutter);
  cam::RasterOptions o;
  o.stepover = 1.0;
  o.step = 0.1;
  const cam::XYBounds b = cam::default_bounds(part.mesh, cutter);
  const cam::RasterPath path = cam::build_raster(engine, b, o);

  // Stock over the part, nodes off any round number so none sits exactly on
  // a wall of the design.
  const geometry::Box3 box = part.mesh.bounds();
  const cam::GridSpec g = cam::GridSpec::covering(box.lo.x + 0.0373, box.lo.y + 0.0411, box.hi.x, box.hi.y, 0.2, 0.2);
  cam::HeightFieldStock stock(g, box.hi.z + 1);
  const geometry::Vec3 start = path.rows.front().front();
  stock.cut_segment(start + geometry::Vec3{0, 0, 20}, start, cutter);
  geometry::Vec3 at = start;
  for (std::size_t r = 0; r < path.rows.size(); ++r) {
    for (const auto& p : path.rows[r]) {
      stock.cut_segment(at, p, cutter);
      at = p;
    }
    if (r < path.links.size())
      for (const auto& p : path.links[r]) {
        stock.cut_segment(at, p, cutter);
        at = p;
      }
  }
  const cam::DesignHeights design = cam::design_heights(part.mesh, g);
  const cam::DeviationResult dev = cam::compare_to_design(stock, design, 1e-3);
  SCOPED_TRACE(dev.stats.summary());
  EXPECT_GT(dev.stats.on_part, g.size() / 2);
  // 1 um: the raster's accepted chord sag is 0.1 um-scale on this part.
  EXPECT_EQ(dev.stats.gouged, 0u);
  if (dev.stats.has_gouge) {
    EXPECT_GT(dev.stats.largest_gouge.value, -1e-3);
  }
  // And the cut really reached the surface: most on-part nodes within the
  // scallop/step-size band of the design.
  EXPECT_LT(dev.stats.mean_excess, 1.0);
  const auto out = std::filesystem::path(CNCSTREAM_BINARY_DIR) / "test-output";
  std::filesystem::create_directories(out);
  cam::write_deviation_png(out / (std::string("plaque-deviation-") + cutter.spec().substr(0, 4) + ".png"), dev,
                      "Plaque finished with " + cutter.description(), "stepover 1 mm, stock grid 0.2 mm");
}

INSTANTIATE_TEST_SUITE_P(Cutters, PlaqueFinish, ::testing::Values("ball:3.175", "bull:3.175:0.79", "flat:3.175"));
