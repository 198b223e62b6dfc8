// Imports of the formats users have: small files written here (and the
// checked-in fixtures under tests/fixtures/tools), each import saying what it
// understood and what it skipped, a malformed file refused with its place.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "cncstream/tooling/tool_import.hpp"

using namespace cncstream::tooling;
namespace fs = std::filesystem;

namespace {

fs::path temp_dir(const std::string& name) {
  const auto d = fs::temp_directory_path() / ("cncstream_tooling_" + std::to_string(::getpid())) / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

void write(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << text;
}

std::string error_of(auto&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no error";
}

bool any_contains(const std::vector<std::string>& lines, const std::string& s) {
  for (const auto& l : lines)
    if (l.find(s) != std::string::npos) return true;
  return false;
}

const fs::path fixtures = fs::path(CNCSTREAM_SOURCE_DIR) / "tests" / "fixtures" / "tools";

}  // namespace

TEST(ToolImport, Fusion360Library) {
  const ImportResult r = import_tool_file(fixtures / "fusion-library.json");
  EXPECT_EQ(r.format, "Fusion 360 tool library");
  ASSERT_EQ(r.tools.size(), 4u) << import_report(r);
  const Tool& flat = r.tools[0];
  EXPECT_EQ(flat.name, "1/4 upcut");
  EXPECT_EQ(flat.number, 1);
  EXPECT_EQ(flat.geometry.spec(), "flat:6.35");  // inches
  EXPECT_EQ(flat.flutes, 2);
  EXPECT_NEAR(flat.flute_length, 25.4, 1e-9);
  const CuttingData* walnut = flat.cutting_for("walnut");
  ASSERT_NE(walnut, nullptr);
  EXPECT_EQ(*walnut->rpm, 18000);
  EXPECT_NEAR(*walnut->feed, 100 * 25.4, 1e-9);  // in/min
  EXPECT_NEAR(*walnut->chip_load, 0.0028 * 25.4, 1e-9);
  EXPECT_EQ(r.tools[1].geometry.spec(), "ball:3.175");
  EXPECT_EQ(r.tools[2].geometry.spec(), "vbit:90:12.7");  // TA 45 per side
  // Tapered mill with a ball tip: TA per side, the top from the flute length.
  const ToolGeometry& taper = r.tools[3].geometry;
  EXPECT_EQ(taper.shape, ToolShape::TaperedBall);
  EXPECT_DOUBLE_EQ(taper.tip_diameter, 1);
  EXPECT_DOUBLE_EQ(taper.angle, 5);
  EXPECT_GT(taper.diameter, 2);
  EXPECT_EQ(r.tools[3].number, 0);  // none in the file
  ASSERT_EQ(r.skipped.size(), 2u) << import_report(r);
  EXPECT_TRUE(any_contains(r.skipped, "/data/4 'M6 drill' (drill): type 'drill' has no shape here")) << import_report(r);
  EXPECT_TRUE(any_contains(r.skipped, "/data/5 'tapered flat' (tapered mill)")) << import_report(r);
  EXPECT_TRUE(any_contains(r.understood, "/data/0 '1/4 upcut' (flat end mill) -> flat:6.35 2 flutes, T1, presets: walnut, mdf"))
      << import_report(r);
}

TEST(ToolImport, MalformedJsonIsRefusedWithItsPlace) {
  EXPECT_NE(error_of([] { import_fusion_library("{\"data\": [", "lib.json"); }).find("lib.json: byte 11"), std::string::npos)
      << error_of([] { import_fusion_library("{\"data\": [", "lib.json"); });
  const std::string e =
      error_of([] { import_fusion_library(R"({"data": [{"type": "flat end mill", "geometry": {"DC": "6"}}]})", "lib.json"); });
  EXPECT_NE(e.find("lib.json: /data/0/geometry/DC: expected a number, got string"), std::string::npos) << e;
  EXPECT_NE(error_of([] { import_fusion_library(R"({"tools": []})", "lib.json"); }).find("lib.json: /:"), std::string::npos);
}

TEST(ToolImport, FreeCadBitAndLibrary) {
  const fs::path dir = temp_dir("freecad");
  write(dir / "Bit" / "taper.fctb", R"({"version": 2, "name": "1mm tapered ball", "shape": "taperedballnose.fcstd",
    "parameter": {"Diameter": "1.00 mm", "TaperAngle": "10.00 °", "TaperDiameter": "3.175 mm",
                  "CuttingEdgeHeight": "15.00 mm", "Length": "50 mm", "ShankDiameter": "3.175 mm", "Flutes": 2},
    "attribute": {"Chipload": "0.03 mm", "Material": "walnut"}})");
  write(dir / "Bit" / "vbit.fctb", R"({"name": "60deg V", "shape": "v-bit.fcstd",
    "parameter": {"Diameter": "0.5 in", "CuttingEdgeAngle": "60 °", "TipDiameter": "0.2 mm"}, "attribute": {}})");
  write(dir / "Bit" / "probe.fctb", R"({"name": "Probe", "shape": "probe.fcstd", "parameter": {"Diameter": "2 mm"}})");
  write(dir / "Bit" / "bull.fctb", R"({"name": "bull", "shape": "bullnose.fcstd",
    "parameter": {"Diameter": "6 mm", "FlatRadius": "2 mm"}})");
  write(dir / "Library" / "shop.fctl", R"({"version": 1, "label": "shop", "tools": [
    {"nr": 3, "path": "taper.fctb"}, {"nr": 5, "path": "vbit.fctb"}, {"nr": 6, "path": "probe.fctb"},
    {"nr": 8, "path": "missing.fctb"}, {"nr": 9, "path": "bull.fctb"}]})");
  const ImportResult r = import_tool_file(dir / "Library" / "shop.fctl");
  ASSERT_EQ(r.tools.size(), 3u) << import_report(r);
  EXPECT_EQ(r.tools[0].number, 3);
  EXPECT_EQ(r.tools[0].geometry.spec(), "taper:1:5:3.175");  // included 10 -> 5 per side
  EXPECT_EQ(r.tools[0].flutes, 2);
  EXPECT_EQ(r.tools[0].flute_length, 15);
  EXPECT_EQ(*r.tools[0].cutting_for("walnut")->chip_load, 0.03);
  EXPECT_EQ(r.tools[1].geometry.spec(), "vbit:60:12.7:0.2");
  EXPECT_EQ(r.tools[2].geometry.spec(), "bull:6:1");
  EXPECT_TRUE(any_contains(r.skipped, "T6 'Probe' (probe): shape 'probe' has no cutter here")) << import_report(r);
  EXPECT_TRUE(any_contains(r.skipped, "T8 missing.fctb: the tool bit file is not beside the library")) << import_report(r);
  // One bit alone.
  const ImportResult one = import_tool_file(dir / "Bit" / "vbit.fctb");
  ASSERT_EQ(one.tools.size(), 1u);
  EXPECT_EQ(one.tools[0].number, 0);
  // A bad quantity names its pointer.
  const std::string e =
      error_of([] { import_freecad_bit(R"({"name": "x", "shape": "endmill", "parameter": {"Diameter": "6 furlongs"}})", "x.fctb"); });
  EXPECT_NE(e.find("x.fctb: /parameter/Diameter: '6 furlongs': unknown unit 'furlongs'"), std::string::npos) << e;
}

TEST(ToolImport, LinuxCncToolTable) {
  const ImportResult r = import_tool_file(fixtures / "tool.tbl");
  ASSERT_EQ(r.tools.size(), 3u) << import_report(r);
  EXPECT_EQ(r.tools[0].number, 1);
  EXPECT_EQ(r.tools[0].name, "1/4 flat end mill");
  EXPECT_EQ(r.tools[0].geometry.spec(), "flat:6.35");
  EXPECT_DOUBLE_EQ(r.tools[0].length_offset, 45.2);
  EXPECT_EQ(r.tools[1].geometry.spec(), "ball:3.175");
  EXPECT_EQ(r.tools[2].name, "T7 3 mm flat end mill");
  EXPECT_TRUE(any_contains(r.understood, "T7 flat:3, length offset 30 mm (shape assumed flat")) << import_report(r);
  EXPECT_TRUE(any_contains(r.skipped, "line 5 'probe' T99: no diameter (D)")) << import_report(r);
  // In inches.
  const ImportResult in = import_linuxcnc_table("T2 P2 D0.125 Z1 ;ball\n", "t.tbl", true);
  EXPECT_EQ(in.tools.at(0).geometry.spec(), "ball:3.175");
  EXPECT_DOUBLE_EQ(in.tools.at(0).length_offset, 25.4);
  // Malformed: the line and column.
  EXPECT_EQ(error_of([] { import_linuxcnc_table("T1 D6\nT2 Dx\n", "tool.tbl"); }),
            "tool.tbl:2: 'Dx' at column 4: expected a number after D");
  EXPECT_NE(error_of([] { import_linuxcnc_table("T1 K6\n", "tool.tbl"); }).find("tool.tbl:1: unexpected 'K' at column 4"),
            std::string::npos);
  EXPECT_NE(error_of([] { import_linuxcnc_table("P1 D6\n", "tool.tbl"); }).find("tool.tbl:1: a tool line without T"),
            std::string::npos);
}

TEST(ToolImport, VectricToolDatabase) {
  const fs::path db_path = temp_dir("vectric") / "tools.vtdb";
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(db_path.c_str(), &db), SQLITE_OK);
  const char* sql = R"(
    CREATE TABLE tool_geometry (id TEXT PRIMARY KEY, name_format TEXT, notes TEXT, tool_type INTEGER, units INTEGER,
      diameter REAL, included_angle REAL, flat_diameter REAL, num_flutes INTEGER, flute_length REAL, tip_radius REAL);
    CREATE TABLE tool_cutting_data (id TEXT PRIMARY KEY, rate_units INTEGER, feed_rate REAL, plunge_rate REAL,
      spindle_speed REAL, stepdown REAL, stepover REAL, clear_stepover REAL, length_units INTEGER, tool_number INTEGER);
    CREATE TABLE tool_entity (id TEXT PRIMARY KEY, material_id TEXT, machine_id TEXT, tool_geometry_id TEXT,
      tool_cutting_data_id TEXT);
    CREATE TABLE material (id TEXT PRIMARY KEY, name TEXT);
    INSERT INTO tool_geometry VALUES ('g1', '1/8" Compression', NULL, 1, 1, 0.125, NULL, NULL, 2, 0.5, NULL);
    INSERT INTO tool_geometry VALUES ('g2', 'V-bit 90', NULL, 3, 0, 12.7, 90, 0, 2, 10, NULL);
    INSERT INTO tool_geometry VALUES ('g3', '{Tool Type} {Diameter}', NULL, 5, 0, 3.175, 10, NULL, 2, 15, 0.5);
    INSERT INTO tool_geometry VALUES ('g4', 'Drill 6', NULL, 6, 0, 6, NULL, NULL, 2, 20, NULL);
    INSERT INTO tool_cutting_data VALUES ('c-master', 4, NULL, NULL, NULL, NULL, NULL, NULL, 0, 7);
    INSERT INTO tool_cutting_data VALUES ('c-acrylic', 4, 100, 65, 19000, 0.08, 0.05, NULL, 1, NULL);
    INSERT INTO tool_cutting_data VALUES ('c-v', 1, 1500, 500, 18000, 2, 0.5, NULL, 0, 12);
    INSERT INTO tool_entity VALUES ('e1', NULL, 'm1', 'g1', 'c-master');
    INSERT INTO tool_entity VALUES ('e2', 'mat-1', 'm1', 'g1', 'c-acrylic');
    INSERT INTO tool_entity VALUES ('e3', 'mat-2', 'm1', 'g2', 'c-v');
    INSERT INTO material VALUES ('mat-1', 'Acrylic');
    INSERT INTO material VALUES ('mat-2', 'MDF');
  )";
  ASSERT_EQ(sqlite3_exec(db, sql, nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
  sqlite3_close(db);
  const ImportResult r = import_tool_file(db_path);
  ASSERT_EQ(r.tools.size(), 3u) << import_report(r);
  const Tool& comp = r.tools[0];
  EXPECT_EQ(comp.name, "1/8\" Compression");
  EXPECT_EQ(comp.number, 7);  // from the master row
  EXPECT_EQ(comp.geometry.spec(), "flat:3.175");
  EXPECT_NEAR(comp.flute_length, 12.7, 1e-9);
  const CuttingData* acr = comp.cutting_for("acrylic");
  ASSERT_NE(acr, nullptr);
  EXPECT_NEAR(*acr->feed, 2540, 1e-9);  // 100 in/min
  EXPECT_NEAR(*acr->plunge_feed, 65 * 25.4, 1e-9);
  EXPECT_EQ(*acr->rpm, 19000);
  EXPECT_NEAR(*acr->stepdown, 0.08 * 25.4, 1e-9);
  EXPECT_EQ(r.tools[1].geometry.spec(), "vbit:90:12.7");
  EXPECT_EQ(r.tools[1].number, 12);
  EXPECT_EQ(*r.tools[1].cutting_for("MDF")->feed, 1500);
  EXPECT_EQ(r.tools[2].geometry.spec(), "taper:1:5:3.175");  // included 10 -> 5 per side
  EXPECT_EQ(r.tools[2].name, "1 mm tapered ball-nose, 5° per side, 3.175 mm at the top");  // a name template: our own
  EXPECT_TRUE(any_contains(r.skipped, "tool_geometry row 4 'Drill 6': tool type 6 (drill)")) << import_report(r);
  // Not a Vectric database: refused naming the file and the missing table.
  const fs::path other = temp_dir("vectric2") / "other.vtdb";
  ASSERT_EQ(sqlite3_open(other.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, "CREATE TABLE unrelated (x)", nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(db);
  EXPECT_EQ(error_of([&] { import_tool_file(other); }),
            other.string() + ": not a Vectric tool database: no table 'tool_geometry'");
  const fs::path text = temp_dir("vectric3") / "text.vtdb";
  write(text, "this is not a database, just some text that is long enough for a header........\n");
  EXPECT_NE(error_of([&] { import_tool_file(text); }).find(text.string() + ": "), std::string::npos);
}

TEST(ToolImport, MergeNumbersAndNames) {
  ToolLibrary lib;
  const ImportResult r = import_tool_file(fixtures / "tool.tbl");
  merge_import(lib, r, false);
  ASSERT_EQ(lib.tools.size(), 3u);
  // Again: the numbers are taken, so the tools get free ones and their names a suffix.
  const auto lines = merge_import(lib, r, false);
  ASSERT_EQ(lib.tools.size(), 6u);
  EXPECT_NE(lines[0].find("(T1 is taken by '1/4 flat end mill')"), std::string::npos) << lines[0];
  ASSERT_NE(lib.by_number(3), nullptr);
  EXPECT_EQ(lib.by_number(3)->name, "1/4 flat end mill (2)");
  // With replace: the same numbers, replaced.
  ToolLibrary again = lib;
  merge_import(again, r, true);
  EXPECT_EQ(again.tools.size(), 6u);
}

TEST(ToolImport, UnknownExtensionIsRefused) {
  EXPECT_NE(error_of([] { import_tool_file("tools.xml"); }).find("tools.xml: unknown tool file"), std::string::npos);
}
