#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <limits>
#include <string>

#include "cncstream/geometry/stl.hpp"

using namespace cncstream;
namespace fs = std::filesystem;

static const fs::path kMeshes = CNCSTREAM_SHARED_MESHES;

TEST(Stl, BinaryAndAsciiGearAgree) {
  const auto a = geometry::load_stl(kMeshes / "gearwheel.ascii.stl");
  const auto b = geometry::load_stl(kMeshes / "gearwheel.bin.stl");
  EXPECT_FALSE(a.binary);
  EXPECT_TRUE(b.binary);
  EXPECT_EQ(a.facets_read, 2444u);
  EXPECT_EQ(b.facets_read, 2444u);
  EXPECT_EQ(a.mesh.triangles.size(), b.mesh.triangles.size());
  const geometry::Box3 ba = a.mesh.bounds(), bb = b.mesh.bounds();
  EXPECT_NEAR(ba.lo.x, bb.lo.x, 1e-4);
  EXPECT_NEAR(ba.hi.z, bb.hi.z, 1e-4);
  EXPECT_NEAR(ba.size().z, 8.0, 1e-3);
}

TEST(Stl, BinaryWhoseHeaderSaysSolidIsReadAsBinary) {
  const auto r = geometry::load_stl(kMeshes / "parser-fixtures/stl-models_broken_wrongHeader.bin.stl");
  EXPECT_TRUE(r.binary);
  EXPECT_EQ(r.mesh.triangles.size(), 12u);
}

TEST(Stl, EveryGoodFixtureLoads) {
  for (const char* name : {"stl-models_polytopes_cube.ascii.stl", "stl-models_polytopes_cube.bin.stl",
                           "stl-models_polytopes_unitCube.ascii.stl", "stl-models_polytopes_unitCube.binary.stl",
                           "stl-models_polytopes_tetrahedron.ascii.stl", "stl-models_polytopes_tetrahedron.bin.stl",
                           "stl-models_polytopes_tetrahedron.min.ascii.stl",
                           "stl-models_polytopes_tetrahedronMinusZero.bin.stl",
                           "stl-models_misc_multiWordName.ascii.stl",
                           "stl-models_polytopes_tetrahedronIrregular.ascii.stl",
                           "stl-models_polytopes_tetrahedronIrregular.bin.stl",
                           "stl-models_polytopes_cubeLarge.ascii.stl",
                           "stl-models_misc_namelessSolid.ascii.stl", "stl-models_misc_faceless.ascii.stl",
                           "stl-models_polytopes_triangle.ascii.stl", "stl-models_polytopes_triangle.bin.stl",
                           "openscad_empty2.stl"}) {
    SCOPED_TRACE(name);
    EXPECT_NO_THROW(geometry::load_stl(kMeshes / "parser-fixtures" / name));
  }
  const auto cube = geometry::load_stl(kMeshes / "parser-fixtures/stl-models_polytopes_cube.ascii.stl");
  const auto s = geometry::summarize(cube.mesh);
  EXPECT_EQ(s.facets, 12u);
  EXPECT_EQ(s.vertices, 8u);
  EXPECT_EQ(s.edges, 18u);
  EXPECT_TRUE(s.closed());
}

// Each broken file is rejected with the file name and the place.
TEST(Stl, BrokenFilesAreRejectedWithPlace) {
  struct Case {
    const char* file;
    const char* where;
  };
  for (const Case& c : {Case{"stl-models_broken_empty.stl", "byte 0"}, Case{"openscad_empty.stl", "byte 0"},
                        Case{"stl-models_broken_fourVertices.ascii.stl", "line 7"},
                        Case{"stl-models_broken_incorrectFaceCounter.bin.stl", "byte 80"},
                        Case{"stl-models_broken_missingEndsolid.ascii.stl", "line"},
                        Case{"stl-models_broken_missingNormal.ascii.stl", "line 24"},
                        Case{"stl-models_broken_notANumberNormal.ascii.stl", "line 9"},
                        Case{"stl-models_broken_quad.ascii.stl", "line"},
                        Case{"stl-models_broken_solidNameMismatch.ascii.stl", "line"},
                        Case{"stl-models_broken_twoVertices.ascii.stl", "line"},
                        Case{"openscad_invalidvertex.stl", "line"},
                        Case{"openscad_toomanyvertices.stl", "line"},
                        Case{"openscad_unparseable.stl", "line 4"},
                        // Its binary body went through a text conversion (U+FFFD bytes).
                        Case{"stl-models_misc_multiWordName.bin.stl", "byte 80"}}) {
    SCOPED_TRACE(c.file);
    try {
      geometry::load_stl(kMeshes / "parser-fixtures" / c.file);
      ADD_FAILURE() << "accepted a broken file";
    } catch (const geometry::StlError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(c.file), std::string::npos) << msg;
      EXPECT_NE(msg.find(c.where), std::string::npos) << msg;
    }
  }
}

TEST(Stl, DegenerateFacetsAreDroppedAndCounted) {
  const auto r = geometry::load_stl(kMeshes / "defects/spider_assimp_degenerate.bin.stl");
  EXPECT_EQ(r.facets_read, 1368u);
  EXPECT_GE(r.dropped_degenerate, 56u);
  EXPECT_EQ(r.mesh.triangles.size() + r.dropped_degenerate, r.facets_read);
  const auto nm = geometry::load_stl(kMeshes / "defects/back_to_back_openscad.ascii.stl");
  const auto s = geometry::summarize(nm.mesh, nm.dropped_degenerate);
  EXPECT_EQ(s.dropped_degenerate, 2u);
  EXPECT_EQ(s.facets, 8u);
}

TEST(Stl, NanAndTruncationInBinary) {
  std::string good(84 + 50, '\0');
  good[80] = 1;
  auto put = [&](std::size_t off, float v) { std::memcpy(good.data() + off, &v, 4); };
  put(84 + 12, 0); put(84 + 24, 1); put(84 + 36 + 4, 1);
  EXPECT_NO_THROW(geometry::parse_stl(good, "mem.stl"));
  std::string nan = good;
  const float q = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(nan.data() + 84 + 28, &q, 4);
  try {
    geometry::parse_stl(nan, "mem.stl");
    ADD_FAILURE();
  } catch (const geometry::StlError& e) {
    EXPECT_NE(std::string(e.what()).find("mem.stl:byte 112"), std::string::npos) << e.what();
  }
  EXPECT_THROW(geometry::parse_stl(good.substr(0, good.size() - 3), "mem.stl"), geometry::StlError);
}

TEST(Stl, AsciiOverflowIsAnErrorAndUnderflowIsZero) {
  auto ascii = [](const std::string& z) {
    return "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 " + z +
           "\nendloop\nendfacet\nendsolid t\n";
  };
  try {
    geometry::parse_stl(ascii("1e400"), "big.stl");
    ADD_FAILURE() << "1e400 read as a number";
  } catch (const geometry::StlError& e) {
    EXPECT_NE(std::string(e.what()).find("big.stl:line 6"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("infinite"), std::string::npos) << e.what();
  }
  EXPECT_THROW(geometry::parse_stl(ascii("-1e400"), "big.stl"), geometry::StlError);
  const auto tiny = geometry::parse_stl(ascii("1e-400"), "tiny.stl");
  EXPECT_EQ(tiny.mesh.bounds().hi.z, 0.0);
}

TEST(Stl, UnitsAndScale) {
  geometry::StlLoadOptions o;
  o.units = geometry::LengthUnit::Inch;
  const auto r = geometry::load_stl(kMeshes / "parser-fixtures/stl-models_polytopes_unitCube.ascii.stl", o);
  EXPECT_NEAR(r.mesh.bounds().size().x, 25.4, 1e-9);
  o.units = geometry::LengthUnit::Metre;
  o.scale = 0.5;
  const auto m = geometry::load_stl(kMeshes / "parser-fixtures/stl-models_polytopes_unitCube.ascii.stl", o);
  EXPECT_NEAR(m.mesh.bounds().size().x, 500.0, 1e-9);
}

TEST(Stl, EveryRealMeshLoads) {
  for (const auto& e : fs::directory_iterator(kMeshes)) {
    if (e.path().extension() != ".stl") continue;
    SCOPED_TRACE(e.path().string());
    const auto r = geometry::load_stl(e.path());
    EXPECT_GT(r.mesh.triangles.size(), 1000u);
  }
}
