// The tool library: specs of every shape, the TOML file both ways, and
// `--tool 3` / `--tool "1/8 tapered ball"` / `--tool ball:3.175`.
#include <gtest/gtest.h>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/tooling/tool_library.hpp"

using namespace cncstream;
using namespace cncstream::tooling;

namespace {

std::string error_of(auto&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no error";
}

ToolLibrary sample() {
  ToolLibrary lib;
  Tool a;
  a.number = 1;
  a.name = "6 mm upcut";
  a.geometry = parse_tool_spec("flat:6");
  a.flutes = 2;
  a.flute_length = 22;
  a.stick_out = 30;
  lib.put(a, false);
  Tool b;
  b.number = 3;
  b.name = "1/8 tapered ball";
  b.geometry = parse_tool_spec("taper:1:5:3.175");
  b.flutes = 2;
  b.overall_length = 76.2;
  CuttingData w;
  w.material = "walnut";
  w.rpm = 18000;
  w.chip_load = 0.03;
  b.cutting.push_back(w);
  lib.put(b, false);
  Tool c;
  c.number = 4;
  c.name = "1/4 tapered ball";
  c.geometry = parse_tool_spec("taper:0.5:3.6:6.35");
  lib.put(c, false);
  Tool d;
  d.number = 7;
  d.name = "60 degree V-bit";
  d.geometry = parse_tool_spec("vbit:60:12.7:0.2");
  d.flutes = 2;
  lib.put(d, false);
  return lib;
}

}  // namespace

TEST(ToolSpec, EveryShapeRoundTrips) {
  for (const char* s : {"flat:6", "ball:3.175", "bull:6:1", "vbit:60:12.7", "vbit:90:12:0.2", "taper:1:5:3.175",
                        "taper:1:5"})
    EXPECT_EQ(parse_tool_spec(s).spec(), s);
  // cam's syntax for lengths: fractions and inches.
  const auto t = parse_tool_spec("taper:1/32in:5:1/8in");
  EXPECT_NEAR(t.tip_diameter, 0.79375, 1e-12);
  EXPECT_NEAR(t.diameter, 3.175, 1e-12);
  // The flat, ball and bull specs are the cam's own: they parse into a Cutter.
  for (const char* s : {"flat:6", "ball:3.175", "bull:6:1"}) EXPECT_EQ(cam::parse_cutter_spec(parse_tool_spec(s).spec()).spec(), s);
  EXPECT_EQ(parse_tool_spec("bull:6:3").shape, ToolShape::Ball);
  EXPECT_EQ(parse_tool_spec("vbit:90:12").description(), "90° V-bit, 12 mm");
  EXPECT_EQ(parse_tool_spec("taper:1:5:3.175").description(), "1 mm tapered ball-nose, 5° per side, 3.175 mm at the top");
}

TEST(ToolSpec, BadSpecsNameThePart) {
  EXPECT_NE(error_of([] { parse_tool_spec("vbit:190:12"); }).find("included angle 190"), std::string::npos);
  EXPECT_NE(error_of([] { parse_tool_spec("vbit:60"); }).find("'vbit' takes"), std::string::npos);
  EXPECT_NE(error_of([] { parse_tool_spec("taper:1:50:3"); }).find("angle per side 50"), std::string::npos);
  EXPECT_NE(error_of([] { parse_tool_spec("taper:3:5:1"); }).find("top diameter 1"), std::string::npos);
  EXPECT_NE(error_of([] { parse_tool_spec("taper:x:5"); }).find("tip diameter 'x'"), std::string::npos);
  EXPECT_NE(error_of([] { parse_tool_spec("drill:6"); }).find("unknown tool type 'drill'"), std::string::npos);
  EXPECT_NE(error_of([] { parse_tool_spec("ball:-1"); }).find("diameter"), std::string::npos);
}

TEST(ToolLibrary, ChoosesByNumberNameOrSpec) {
  const ToolLibrary lib = sample();
  EXPECT_EQ(choose_tool(lib, "3").tool->name, "1/8 tapered ball");
  EXPECT_EQ(choose_tool(lib, "T7").spec(), "vbit:60:12.7:0.2");
  EXPECT_EQ(choose_tool(lib, "1/8 Tapered Ball").tool->number, 3);  // whole name, any case
  EXPECT_EQ(choose_tool(lib, "upcut").tool->number, 1);             // the one name containing it
  const ToolChoice spec = choose_tool(lib, "ball:3.175");
  EXPECT_EQ(spec.tool, nullptr);
  EXPECT_EQ(spec.spec(), "ball:3.175");
  // Ambiguous: both candidates listed.
  const std::string amb = error_of([&] { choose_tool(lib, "tapered ball"); });
  EXPECT_NE(amb.find("ambiguous"), std::string::npos) << amb;
  EXPECT_NE(amb.find("T3 '1/8 tapered ball'"), std::string::npos) << amb;
  EXPECT_NE(amb.find("T4 '1/4 tapered ball'"), std::string::npos) << amb;
  // Unknown name or number: the library's tools listed.
  const std::string unknown = error_of([&] { choose_tool(lib, "fishtail"); });
  EXPECT_NE(unknown.find("no tool named 'fishtail'"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("T7 '60 degree V-bit'"), std::string::npos) << unknown;
  EXPECT_NE(error_of([&] { choose_tool(lib, "12"); }).find("no tool number 12"), std::string::npos);
  EXPECT_NE(error_of([&] { choose_tool(ToolLibrary{}, "3"); }).find("library is empty"), std::string::npos);
}

TEST(ToolLibrary, PutRefusesTakenNumbersAndNames) {
  ToolLibrary lib = sample();
  Tool t;
  t.number = 3;
  t.name = "another";
  t.geometry = parse_tool_spec("flat:3");
  EXPECT_NE(error_of([&] { lib.put(t, false); }).find("number 3 is taken by '1/8 tapered ball' (replace it, or use number 2)"),
            std::string::npos);
  t.number = 9;
  t.name = "6 MM UPCUT";
  EXPECT_NE(error_of([&] { lib.put(t, false); }).find("taken by T1"), std::string::npos);
  t.name = "another";
  lib.put(t, false);
  EXPECT_EQ(lib.tools.back().number, 9);
  t.number = 3;
  EXPECT_NE(error_of([&] { lib.put(t, true); }).find("the name 'another' is taken by T9"), std::string::npos);
  t.name = "yet another";
  lib.put(t, true);  // replaces T3
  EXPECT_EQ(lib.by_number(3)->name, "yet another");
  lib.remove(3);
  EXPECT_EQ(lib.by_number(3), nullptr);
  EXPECT_THROW(lib.remove(3), std::invalid_argument);
  EXPECT_EQ(lib.free_number(), 2);
}

TEST(ToolLibrary, TomlRoundTrip) {
  const ToolLibrary lib = sample();
  const std::string text = format_tool_library(lib);
  const ToolLibrary back = parse_tool_library(text, "tools.toml");
  ASSERT_EQ(back.tools.size(), lib.tools.size());
  for (std::size_t k = 0; k < lib.tools.size(); ++k) {
    const Tool &a = lib.tools[k], &b = back.tools[k];
    EXPECT_EQ(a.number, b.number);
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.geometry.spec(), b.geometry.spec());
    EXPECT_EQ(a.flutes, b.flutes);
    EXPECT_EQ(a.flute_length, b.flute_length);
    EXPECT_EQ(a.stick_out, b.stick_out);
    EXPECT_EQ(a.overall_length, b.overall_length);
    ASSERT_EQ(a.cutting.size(), b.cutting.size());
  }
  const CuttingData* w = back.by_number(3)->cutting_for("Walnut");
  ASSERT_NE(w, nullptr);
  EXPECT_EQ(w->rpm, 18000);
  EXPECT_EQ(w->chip_load, 0.03);
  EXPECT_FALSE(w->feed);
  EXPECT_EQ(format_tool_library(back), text);
}

TEST(ToolLibrary, MalformedFileIsRefusedWithItsLine) {
  auto err = [](const std::string& text) { return error_of([&] { parse_tool_library(text, "tools.toml"); }); };
  EXPECT_NE(err("[[tool]]\nnumber = 1\nname = \"a\"\nshape = \"ball:x\"\n").find("tools.toml:4: tool 1: bad cutter spec"),
            std::string::npos)
      << err("[[tool]]\nnumber = 1\nname = \"a\"\nshape = \"ball:x\"\n");
  EXPECT_NE(err("[[tool]]\nnumber = 1\nname = \"a\"\nshape = \"ball:3\"\ncolour = 2\n").find("tools.toml:5: tool.colour: unknown key"),
            std::string::npos);
  EXPECT_NE(err("[[tool]]\nnumber = 1.5\nname = \"a\"\nshape = \"ball:3\"\n").find("tools.toml:2"), std::string::npos);
  EXPECT_NE(err("[[tool]]\nnumber = 1\nname = \"a\"\nshape = \"ball:3\"\n[[tool]]\nnumber = 1\nname = \"b\"\nshape = \"ball:3\"\n")
                .find("tools.toml:5: tool number 1 is taken"),
            std::string::npos);
  EXPECT_NE(err("[[tool]\n").find("tools.toml:1"), std::string::npos);
  EXPECT_NE(err("[[tool]]\nnumber = 2\nshape = \"ball:3\"\n").find("no name"), std::string::npos);
  EXPECT_TRUE(parse_tool_library("", "tools.toml").tools.empty());
}
