// CL engine on every real mesh of /work/shared/meshes and the example
// plaque: no gouge and touched at random nodes (independent oracle),
// height_at against the oracle off the grid, and leaving out concave edges
// against drawing every edge at all nodes.
#include <gtest/gtest.h>

#include <cmath>
#include <ostream>
#include <random>
#include <string>
#include <vector>

#include "cam/cl_cutter_tools.hpp"
#include "cam/cl_oracle.hpp"
#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/geometry/stl.hpp"

using namespace cncstream;

namespace {

struct RealMesh {
  std::string file;
  double scale;     // to about 100 mm
  bool y_up;        // rotate so that +Y becomes +Z
};

void PrintTo(const RealMesh& r, std::ostream* os) { *os << r.file; }

geometry::Mesh load(const RealMesh& r) {
  const std::string dir = CNCSTREAM_SHARED_MESHES;
  const std::string path = r.file == "plaque" ? std::string(CNCSTREAM_SOURCE_DIR) + "/examples/plaque.stl" : dir + "/" + r.file;
  geometry::Mesh m = geometry::load_stl(path).mesh;
  if (r.y_up)
    for (auto& v : m.vertices) v = {v.x, -v.z, v.y};
  m.scale(r.scale);
  return m;
}

using cl_oracle::tool_of;

class ClRealMesh : public ::testing::TestWithParam<RealMesh> {};

TEST_P(ClRealMesh, NoGougeTouchedAndConcaveEdgesRedundant) {
  const geometry::Mesh m = load(GetParam());
  ASSERT_GT(m.triangles.size(), 0u);
  const geometry::Box3 b = m.bounds();
  const double span = std::fmax(b.size().x, b.size().y);
  const std::vector<std::size_t> by_top = cl_oracle::facets_by_top(m);
  std::mt19937 rng(42);
  for (const cam::Cutter& c : {cam::Cutter::ball(6), cam::Cutter::flat(6), cam::Cutter::bull(6, 1), cam::Cutter::vbit(60, 6),
                         cam::Cutter::tapered_ball(1, 5, 6)}) {
    SCOPED_TRACE(GetParam().file + " " + c.spec());
    const double step = span / 90;
    const cam::GridSpec spec = cam::GridSpec::covering(b.lo.x - 2, b.lo.y - 2, b.hi.x + 2, b.hi.y + 2, step, step * 1.07);
    const cam::ClEngine engine(m, c);
    const cam::ClGrid g = engine.compute(spec);
    // Every edge drawn in full, versus valley edges left out and ridge edges
    // trimmed to their normal-cone band (the default).
    cam::ClOptions every_edge;
    every_edge.skip_concave_edges = false;
    const cam::ClGrid full = cam::ClEngine(m, c, every_edge).compute(spec);
    double worst = 0;
    for (std::size_t k = 0; k < g.z.size(); ++k) worst = std::fmax(worst, std::fabs(g.z[k] - full.z[k]));
    EXPECT_LE(worst, 1e-8) << "leaving out concave edges changed the envelope";
    EXPECT_EQ(g.on_floor, full.on_floor);

    const cl_oracle::Tool t = tool_of(c);
    std::uniform_int_distribution<std::size_t> node(0, spec.size() - 1);
    std::uniform_real_distribution<double> ux(b.lo.x, b.hi.x), uy(b.lo.y, b.hi.y);
    for (int sample = 0; sample < 12; ++sample) {
      const std::size_t k = node(rng);
      const double x = spec.x(k % spec.nx), y = spec.y(k / spec.nx);
      const cl_oracle::MeshDrop o = cl_oracle::mesh_drop(m, by_top, t, x, y);
      if (o.drop == cl_oracle::kNone) {
        EXPECT_EQ(g.on_floor[k], 1) << x << "," << y;
        continue;
      }
      EXPECT_GE(g.z[k], o.drop - 1e-6) << "gouge at " << x << "," << y;
      EXPECT_LE(g.z[k], o.drop + 1e-6) << "not touching at " << x << "," << y;
      // Off the grid, through the point query.
      const double px = ux(rng), py = uy(rng);
      const cl_oracle::MeshDrop op = cl_oracle::mesh_drop(m, by_top, t, px, py);
      bool on_floor = false;
      const double zp = engine.height_at(px, py, on_floor);
      if (op.drop == cl_oracle::kNone) {
        EXPECT_TRUE(on_floor);
      } else {
        EXPECT_NEAR(zp, op.drop, 1e-6) << "height_at " << px << "," << py;
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    Shared, ClRealMesh,
    ::testing::Values(RealMesh{"plaque", 1.0, false}, RealMesh{"lion_head_relief.stl", 120.0, false},
                      RealMesh{"fandisk.stl", 100.0, false}, RealMesh{"gearwheel.bin.stl", 2.5, false},
                      RealMesh{"tr12j_housing_occt.stl", 0.24, false}, RealMesh{"bunny_stanford.bin.stl", 700.0, true},
                      RealMesh{"defects/spider_assimp_degenerate.bin.stl", 1.0, false},
                      RealMesh{"defects/back_to_back_openscad.ascii.stl", 10.0, false}),
    [](const ::testing::TestParamInfo<RealMesh>& info) {
      std::string n = info.param.file.substr(info.param.file.rfind('/') + 1);
      n = n.substr(0, n.find('.'));
      for (auto& ch : n)
        if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
      return n;
    });

}  // namespace
