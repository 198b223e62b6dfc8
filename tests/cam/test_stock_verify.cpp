// Design comparison (ray-cast heights, deviation statistics) and the
// machined-result exports (height-field files, closed STL).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "cncstream/cam/deviation.hpp"
#include "cncstream/cam/height_field_io.hpp"
#include "cncstream/cam/height_field_mesh.hpp"
#include "cncstream/geometry/stl.hpp"
#include "cncstream/image/image.hpp"

using namespace cncstream;

namespace {

std::filesystem::path out_dir() {
  auto d = std::filesystem::path(CNCSTREAM_BINARY_DIR) / "test-output" / "stock";
  std::filesystem::create_directories(d);
  return d;
}

// Axis-aligned box [0, sx] x [0, sy] x [0, sz], outward winding.
geometry::Mesh box(double sx, double sy, double sz) {
  geometry::Mesh m;
  for (int k = 0; k < 8; ++k) m.vertices.push_back({(k & 1) ? sx : 0, (k & 2) ? sy : 0, (k & 4) ? sz : 0});
  const std::uint32_t f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                  {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const auto& t : f) m.triangles.push_back({t[0], t[1], t[2]});
  return m;
}

// UV sphere with its vertices on the sphere (faces lie inside it).
geometry::Mesh sphere(double r, int nu, int nv) {
  geometry::Mesh m;
  for (int v = 0; v <= nv; ++v)
    for (int u = 0; u < nu; ++u) {
      const double th = std::numbers::pi * v / nv, ph = 2 * std::numbers::pi * u / nu;
      m.vertices.push_back({r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph), r * std::cos(th)});
    }
  auto id = [&](int u, int v) { return static_cast<std::uint32_t>(v * nu + (u % nu)); };
  for (int v = 0; v < nv; ++v)
    for (int u = 0; u < nu; ++u) {
      m.triangles.push_back({id(u, v), id(u, v + 1), id(u + 1, v + 1)});
      m.triangles.push_back({id(u, v), id(u + 1, v + 1), id(u + 1, v)});
    }
  return m;
}

}  // namespace

TEST(DesignHeights, BoxTopIsTheTopMostHit) {
  const auto g = cam::GridSpec::covering(-2, -2, 12, 10, 0.5, 0.5);
  const auto d = cam::design_heights(box(10, 8, 5), g);
  for (std::size_t j = 0; j < g.ny; ++j)
    for (std::size_t i = 0; i < g.nx; ++i) {
      const double x = g.x(i), y = g.y(j);
      const bool inside = x >= 0 && x <= 10 && y >= 0 && y <= 8;
      const std::size_t k = j * g.nx + i;
      EXPECT_EQ(d.off_part[k], inside ? 0 : 1) << x << "," << y;
      if (inside) {
        EXPECT_DOUBLE_EQ(d.z[k], 5.0) << x << "," << y;
      } else {
        EXPECT_TRUE(std::isnan(d.z[k]));
      }
    }
  EXPECT_EQ(d.on_part, 21u * 17u);
}

TEST(DesignHeights, SphereTopWithinTessellationError) {
  const auto g = cam::GridSpec::covering(-6, -6, 6, 6, 0.25, 0.25);
  const double R = 5;
  const auto d = cam::design_heights(sphere(R, 96, 48), g);
  // Chord sag of the tessellation: R (1 - cos(pi / 48)).
  const double sag = R * (1 - std::cos(std::numbers::pi / 48)) * 1.5;
  for (std::size_t j = 0; j < g.ny; ++j)
    for (std::size_t i = 0; i < g.nx; ++i) {
      const double r = std::hypot(g.x(i), g.y(j));
      const std::size_t k = j * g.nx + i;
      if (r < 4.5) {
        ASSERT_FALSE(d.off_part[k]);
        const double want = std::sqrt(R * R - r * r);
        EXPECT_LE(d.z[k], want + 1e-9);
        EXPECT_GE(d.z[k], want - sag / std::cos(std::asin(r / R))) << r;
      }
      if (r > R + 1e-9) {
        EXPECT_TRUE(d.off_part[k]) << r;
      }
    }
}

TEST(DesignHeights, RealMeshStaysInsideItsBounds) {
  const auto mesh = geometry::load_stl(std::filesystem::path(CNCSTREAM_SHARED_MESHES) / "gearwheel.bin.stl").mesh;
  const geometry::Box3 b = mesh.bounds();
  const auto g = cam::GridSpec::covering(b.lo.x - 1, b.lo.y - 1, b.hi.x + 1, b.hi.y + 1, 0.5, 0.5);
  const auto d = cam::design_heights(mesh, g);
  EXPECT_GT(d.on_part, g.size() / 3);
  EXPECT_LT(d.on_part, g.size());
  for (std::size_t k = 0; k < g.size(); ++k)
    if (!d.off_part[k]) {
      EXPECT_GE(d.z[k], b.lo.z - 1e-9);
      EXPECT_LE(d.z[k], b.hi.z + 1e-9);
    }
}

TEST(Deviation, KnownGougeAndExcess) {
  const auto g = cam::GridSpec::covering(-2, -2, 12, 10, 0.25, 0.25);
  const auto design = cam::design_heights(box(10, 8, 5), g);
  cam::HeightFieldStock stock(g, 5.3);  // 0.3 mm left everywhere...
  stock.cut_segment({3, 2, 8}, {3, 2, 4.8}, cam::Cutter::flat(2));  // ...but a 0.2 mm deep hole at (3, 2)
  const auto r = cam::compare_to_design(stock, design, 0.05);
  const auto& s = r.stats;
  ASSERT_TRUE(s.has_gouge);
  EXPECT_NEAR(s.largest_gouge.value, -0.2, 1e-12);
  EXPECT_LE(std::hypot(s.largest_gouge.x - 3, s.largest_gouge.y - 2), 1.0);
  EXPECT_NEAR(s.largest_excess.value, 0.3, 1e-12);
  // Nodes within 1 mm of (3, 2) on a 0.25 grid: count them directly.
  std::size_t hole = 0;
  for (std::size_t j = 0; j < g.ny; ++j)
    for (std::size_t i = 0; i < g.nx; ++i) hole += std::hypot(g.x(i) - 3, g.y(j) - 2) <= 1 + 1e-9;
  EXPECT_EQ(s.gouged, hole);
  EXPECT_EQ(s.on_part, 41u * 33u);
  EXPECT_EQ(s.excess, s.on_part - hole);
  EXPECT_NEAR(s.mean_excess, 0.3 * static_cast<double>(s.on_part - hole) / s.on_part, 1e-12);
  EXPECT_NE(s.summary().find("largest gouge 0.2000 mm"), std::string::npos) << s.summary();
  // 0.3 mm left on all but the hole's ~4 % of the nodes.
  EXPECT_NEAR(s.excess_p50, 0.3, 1e-12);
  EXPECT_NEAR(s.excess_p99, 0.3, 1e-12);
  EXPECT_NEAR(s.excess_rms, 0.3 * std::sqrt(static_cast<double>(s.on_part - hole) / s.on_part), 1e-12);
  EXPECT_NE(s.summary().find("median 0.3000 mm, 90% 0.3000 mm, 99% 0.3000 mm"), std::string::npos) << s.summary();

  // The map: gouge pixels where the hole is, excess over the rest of the box.
  const auto img = cam::render_deviation(r, "Deviation test", "flat 2 mm hole", 400);
  image::write_png(out_dir() / "deviation_known.png", img);
  const image::Rgb gouge = image::DeviationPalette::gouge(1), excess = image::DeviationPalette::excess(1);
  double gx = 0, gy = 0, gn = 0, en = 0;
  int ex0 = 1 << 30, ex1 = -1, ey0 = 1 << 30, ey1 = -1;
  for (int y = 0; y < img.height(); ++y)
    for (int x = 0; x < 16 + 400; ++x) {  // the map area (legend is to its right)
      const image::Rgb c = img.get(x, y);
      if (c == gouge) gx += x, gy += y, ++gn;
      if (c == excess || c == gouge) {
        ++en;
        ex0 = std::min(ex0, x), ex1 = std::max(ex1, x), ey0 = std::min(ey0, y), ey1 = std::max(ey1, y);
      }
    }
  ASSERT_GT(gn, 20);
  // The box [0, 10] x [0, 8]: the hole's centre at 30% across, 25% up.
  EXPECT_NEAR((gx / gn - ex0) / (ex1 - ex0), 0.3, 0.03);
  EXPECT_NEAR((ey1 - gy / gn) / (ey1 - ey0), 0.25, 0.03);
  EXPECT_NEAR(gn / en, std::numbers::pi / 80, 0.01);
}

TEST(Deviation, RejectsMismatchedGrid) {
  const auto g = cam::GridSpec::covering(0, 0, 10, 8, 0.5, 0.5);
  const auto design = cam::design_heights(box(10, 8, 5), g);
  cam::HeightFieldStock other(cam::GridSpec::covering(0, 0, 10, 8, 0.25, 0.25), 6);
  EXPECT_THROW(cam::compare_to_design(other, design, 0.05), std::invalid_argument);
  cam::HeightFieldStock same(g, 6);
  EXPECT_THROW(cam::compare_to_design(same, design, 0), std::invalid_argument);
}

TEST(HeightFieldFiles, RoundTrip) {
  const auto g = cam::GridSpec::covering(-3, 2, 7, 9, 0.1, 0.2);
  cam::HeightFieldStock s(g, 1.5);
  s.cut_segment({-2, 3, 0.2}, {6, 8, -0.5}, cam::Cutter::ball(3));
  const auto path = out_dir() / "groove.f32";
  cam::write_height_field(path, g, s.heights());
  EXPECT_EQ(std::filesystem::file_size(path), g.size() * 4);
  const auto back = cam::read_height_field(path);
  EXPECT_EQ(back.grid.nx, g.nx);
  EXPECT_EQ(back.grid.ny, g.ny);
  EXPECT_DOUBLE_EQ(back.grid.x0, g.x0);
  EXPECT_DOUBLE_EQ(back.grid.dy, g.dy);
  ASSERT_EQ(back.z.size(), g.size());
  for (std::size_t k = 0; k < g.size(); ++k) ASSERT_EQ(back.z[k], static_cast<float>(s.heights()[k]));
  // NaN survives (off-part nodes).
  std::vector<double> z(g.size(), 1.0);
  z[5] = std::nan("");
  cam::write_height_field(path, g, z);
  EXPECT_TRUE(std::isnan(cam::read_height_field(path).z[5]));
  EXPECT_FALSE(cam::read_height_field(path).work_offset);
  // A machined surface in work coordinates says where the model sat.
  cam::write_height_field(path, g, z, geometry::Vec3{1.25, 0, -10.5});
  const auto placed = cam::read_height_field(path);
  ASSERT_TRUE(placed.work_offset);
  EXPECT_EQ(*placed.work_offset, (geometry::Vec3{1.25, 0, -10.5}));
}

TEST(HeightFieldFiles, ErrorsNameTheFile) {
  const auto g = cam::GridSpec::covering(0, 0, 1, 1, 0.5, 0.5);
  const auto path = out_dir() / "bad.f32";
  cam::write_height_field(path, g, std::vector<double>(g.size(), 0.0));
  std::filesystem::resize_file(path, 10);
  try {
    cam::read_height_field(path);
    FAIL();
  } catch (const cam::HeightFieldError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.f32: expected 36 bytes"), std::string::npos) << e.what();
  }
  {
    std::ofstream(cam::height_field_sidecar(path)) << "cncstream height field 1\nnx 3\nny three\n";
  }
  try {
    cam::read_height_field(path);
    FAIL();
  } catch (const cam::HeightFieldError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.f32.txt:3: 'three' is not a number"), std::string::npos) << e.what();
  }
  EXPECT_THROW(cam::read_height_field(out_dir() / "missing.f32"), cam::HeightFieldError);
  cam::write_height_field(path, g, std::vector<double>(g.size(), 0.0));
  std::ofstream(cam::height_field_sidecar(path), std::ios::app) << "work_offset_z -10.5\n";
  try {
    cam::read_height_field(path);
    FAIL() << "a partial work offset was taken";
  } catch (const cam::HeightFieldError& e) {
    EXPECT_NE(std::string(e.what()).find("work_offset_x, work_offset_y and work_offset_z go together"), std::string::npos)
        << e.what();
  }
}

TEST(HeightFieldSolid, ClosedAndEnclosesTheVolume) {
  const auto g = cam::GridSpec::covering(0, 0, 6, 4, 0.5, 0.5);
  cam::HeightFieldStock s(g, 2.0);
  s.cut_segment({1, 1, 1}, {5, 3, 0.5}, cam::Cutter::ball(2));
  const double bottom = -1;
  const auto path = out_dir() / "machined.stl";
  cam::write_height_field_stl(path, g, s.heights(), bottom);
  const auto loaded = geometry::load_stl(path);
  const auto summary = geometry::summarize(loaded.mesh);
  EXPECT_TRUE(summary.closed()) << summary.to_string();
  EXPECT_EQ(summary.facets, 2 * (g.nx - 1) * (g.ny - 1) + 3 * 2 * (g.nx - 1 + g.ny - 1));
  // Signed volume (divergence theorem) equals the prisms under the top triangles.
  const geometry::Mesh m = cam::height_field_solid(g, s.heights(), bottom);
  double vol = 0;
  for (std::size_t t = 0; t < m.size(); ++t) vol += dot(m.corner(t, 0), cross(m.corner(t, 1), m.corner(t, 2))) / 6;
  double want = 0;
  for (std::size_t j = 0; j + 1 < g.ny; ++j)
    for (std::size_t i = 0; i + 1 < g.nx; ++i) {
      const double a = s.at(i, j), b = s.at(i + 1, j), c = s.at(i + 1, j + 1), d = s.at(i, j + 1);
      want += g.dx * g.dy / 2 * ((a + b + c) / 3 - bottom) + g.dx * g.dy / 2 * ((a + c + d) / 3 - bottom);
    }
  EXPECT_NEAR(vol, want, 1e-9 * want);
  EXPECT_THROW(cam::height_field_solid(g, s.heights(), 0.6), std::invalid_argument);
}

#include "cncstream/image/height_map.hpp"

TEST(MachinedPicture, HeightMapOfAFinishedPocket) {
  // Rough a pocket with a flat end mill, then a ball-nose raster over a dome:
  // the picture shows walls, scallops and the untouched rim.
  const auto g = cam::GridSpec::covering(0, 0, 60, 40, 0.1, 0.1);
  cam::HeightFieldStock s(g, 0.0);
  const auto flat = cam::Cutter::flat(6), ball = cam::Cutter::ball(3.175);
  for (double y = 8; y <= 32; y += 4) s.cut_segment({8, y, -1.5}, {52, y, -1.5}, flat);
  for (double y = 8; y <= 32; y += 1.0) {
    geometry::Vec3 p{8, y, -1.5};
    for (double x = 8.5; x <= 52; x += 0.5) {
      const double z = -1.5 - 2.5 * std::exp(-((x - 30) * (x - 30) + (y - 20) * (y - 20)) / 60);
      const geometry::Vec3 q{x, y, z};
      s.cut_segment(p, q, ball);
      p = q;
    }
  }
  const image::MapGrid mg{g.nx, g.ny, g.dx, g.dy, g.x0, g.y0};
  image::HeightMapOptions o;
  o.title = "Machined stock";
  o.subtitle = "flat 6 mm roughing, ball 3.175 mm finish, 1 mm stepover";
  const auto img = image::render_height_map(mg, s.heights(), {}, o);
  image::write_png(out_dir() / "machined_height_map.png", img);
  EXPECT_GT(img.width(), 800);
  EXPECT_LT(s.heights()[0], 1e-12);
}

TEST(Deviation, ScallopPercentilesOfAKnownDistribution) {
  // A design block with its top at Z1 and a machined surface left k/100 mm
  // high in column k (k = 0..99): the material left is uniform on 0..0.99 mm.
  const auto g = cam::GridSpec::covering(0, 0, 99, 9, 1, 1);
  ASSERT_EQ(g.nx, 100u);
  const auto design = cam::design_heights(box(100, 20, 1), g);
  std::vector<double> z(g.size());
  for (std::size_t k = 0; k < g.size(); ++k) z[k] = 1 + static_cast<double>(k % g.nx) / 100.0;
  const cam::HeightFieldStock stock(g, 2.0, z);
  const auto s = cam::compare_to_design(stock, design, 0.05).stats;
  ASSERT_EQ(s.on_part, g.size());
  EXPECT_NEAR(s.excess_p50, 0.49, 1e-12);  // nearest rank: the 500th of 1000
  EXPECT_NEAR(s.excess_p90, 0.89, 1e-12);
  EXPECT_NEAR(s.excess_p99, 0.98, 1e-12);
  double sq = 0;
  for (int k = 0; k < 100; ++k) sq += (k / 100.0) * (k / 100.0);
  EXPECT_NEAR(s.excess_rms, std::sqrt(sq / 100), 1e-12);
}
