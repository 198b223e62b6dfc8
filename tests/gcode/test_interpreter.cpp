#include <gtest/gtest.h>

#include <cmath>

#include "cncstream/gcode/arc_segments.hpp"
#include "cncstream/gcode/interpreter.hpp"
#include "cncstream/gcode/line_lexer.hpp"

using namespace cncstream;
using namespace cncstream::gcode;

namespace {

BlockResult run(const ParserState& s, std::string_view raw) {
  const CleanLine c = clean_line(raw);
  return execute_block(s, c.text);
}

ParserState run_ok(const ParserState& s, std::string_view raw) {
  BlockResult r = run(s, raw);
  EXPECT_TRUE(r.ok()) << raw << " -> error:" << r.status;
  return r.state;
}

int status_of(std::string_view raw, const ParserState& s = {}) { return run(s, raw).status; }

}  // namespace

TEST(LineLexer, CleansLikeTheFirmware) {
  EXPECT_EQ(clean_line("g1 x1.5 (comment) y-2 ; rest").text, "G1X1.5Y-2");
  EXPECT_EQ(clean_line("/G0 X0\r").text, "G0X0");
  EXPECT_EQ(clean_line("(unterminated G1 X5").text, "");
  EXPECT_FALSE(clean_line(std::string(79, 'X')).overflow);
  EXPECT_TRUE(clean_line(std::string(80, 'X')).overflow);
  EXPECT_EQ(grbl_line_cost("G1 X1 ; hi"), 5u);
}

TEST(LineLexer, AssemblerSplitsOnCrAndLf) {
  LineAssembler a;
  int lines = 0;
  for (char c : std::string("G0\r\nG1\n")) lines += a.push(c).has_value();
  EXPECT_EQ(lines, 3);  // "\r\n" is two line ends, as on the firmware
}

TEST(LineLexer, NumbersAndLetters) {
  auto r = lex_words("G1X-.5Y+2.");
  ASSERT_EQ(r.status, 0);
  ASSERT_EQ(r.words.size(), 3u);
  EXPECT_DOUBLE_EQ(r.words[1].value, -0.5);
  EXPECT_DOUBLE_EQ(r.words[2].value, 2.0);
  EXPECT_EQ(lex_words("G1X").status, 2);
  EXPECT_EQ(lex_words("G1X1.2.3").status, 1);
  EXPECT_EQ(lex_words("1G1").status, 1);
  EXPECT_EQ(lex_words("G1X1E5").status, 0);  // E is a letter here; the parser rejects it
}

TEST(Interpreter, GrblErrorCodes) {
  ParserState fed = run_ok({}, "G1 X0 F100");
  EXPECT_EQ(status_of("X"), 2);
  EXPECT_EQ(status_of("1"), 1);
  EXPECT_EQ(status_of("M6"), 20);
  EXPECT_EQ(status_of("G5"), 20);
  EXPECT_EQ(status_of("E1"), 20);
  EXPECT_EQ(status_of("G0 G1 X1"), 24);  // two motion commands need axis words
  EXPECT_EQ(status_of("G17 G18"), 21);   // same modal group
  EXPECT_EQ(status_of("G90 G91"), 21);
  EXPECT_EQ(status_of("M3 M5"), 21);
  EXPECT_EQ(status_of("G1 X1"), 22);     // no feed yet
  EXPECT_EQ(status_of("G1.5 X1"), 23);
  EXPECT_EQ(status_of("G0 X1 X2"), 25);
  EXPECT_EQ(status_of("G92"), 26);
  EXPECT_EQ(status_of("N99999999 G0 X1"), 27);
  EXPECT_EQ(status_of("G4"), 28);
  EXPECT_EQ(status_of("G10 X1"), 28);
  EXPECT_EQ(status_of("G10 L2 P7 X1"), 29);
  EXPECT_EQ(status_of("G53 G2 X1 I1 F10"), 30);
  EXPECT_EQ(status_of("G80 X1"), 31);
  EXPECT_EQ(status_of("G2 Z1 I1", fed), 32);
  EXPECT_EQ(status_of("G2 X0 Y0 R5", fed), 33);
  EXPECT_EQ(status_of("G2 X10 R2", fed), 34);
  EXPECT_EQ(status_of("G2 X10", fed), 35);
  EXPECT_EQ(status_of("G2 X10 I3", fed), 33);  // end not on the circle
  EXPECT_EQ(status_of("G0 X1 I1"), 36);
  EXPECT_EQ(status_of("G43.1 X1"), 37);
  EXPECT_EQ(status_of("T300"), 38);
  EXPECT_EQ(status_of("F-1"), 4);
  EXPECT_EQ(status_of("G38.1 Z-1 F10"), 20);
  EXPECT_EQ(status_of("G90.1"), 20);
}

TEST(Interpreter, ErrorLeavesStateUntouched) {
  ParserState s = run_ok({}, "G91 G1 X1 F100");
  BlockResult r = run(s, "G90 G0 X5 X6");
  EXPECT_EQ(r.status, 25);
  EXPECT_TRUE(r.state.modal.incremental);
  EXPECT_EQ(r.state.position, (geometry::Vec3{1, 0, 0}));
}

TEST(Interpreter, ModalMotionAndUnits) {
  ParserState s = run_ok({}, "G20 G1 X1 F10");
  EXPECT_NEAR(s.position.x, 25.4, 1e-12);
  EXPECT_NEAR(s.feed_rate, 254, 1e-9);
  BlockResult r = run(s, "Y1");  // modal G1 with inches
  ASSERT_TRUE(r.ok());
  ASSERT_EQ(r.actions.size(), 1u);
  const auto& m = std::get<LinearMove>(r.actions[0]);
  EXPECT_FALSE(m.rapid);
  EXPECT_NEAR(m.to.y, 25.4, 1e-12);
  s = run_ok(r.state, "G21 G91 G0 X-25.4 Z2");
  EXPECT_NEAR(s.position.x, 0, 1e-12);
  EXPECT_NEAR(s.position.z, 2, 1e-12);
  EXPECT_EQ(format_modes(s), "[GC:G0 G54 G17 G21 G91 G94 M5 M9 T0 F254 S0]");
}

TEST(Interpreter, WorkOffsetsG10G92G54) {
  ParserState s = run_ok({}, "G10 L2 P2 X10 Y20 Z-5");
  EXPECT_EQ(s.coords.wcs[1], (geometry::Vec3{10, 20, -5}));
  s = run_ok(s, "G55 G0 X1 Y1 Z1");
  EXPECT_EQ(s.position, (geometry::Vec3{11, 21, -4}));
  s = run_ok(s, "G92 X0 Y0");  // here is now work 0,0
  EXPECT_NEAR(s.work_position().x, 0, 1e-12);
  EXPECT_NEAR(s.work_position().z, 1, 1e-12);
  s = run_ok(s, "G92.1");
  EXPECT_NEAR(s.work_position().x, 1, 1e-12);
  s = run_ok(s, "G10 L20 P0 X5");  // current position becomes X5 in G55
  EXPECT_NEAR(s.work_position().x, 5, 1e-12);
  EXPECT_NEAR(s.coords.wcs[1].x, 6, 1e-12);
  s = run_ok(s, "G53 G0 X0");
  EXPECT_NEAR(s.position.x, 0, 1e-12);
}

TEST(Interpreter, G28AndG30) {
  ParserState s = run_ok({}, "G0 X5 Y6 Z7");
  s = run_ok(s, "G28.1");
  EXPECT_EQ(s.coords.g28, (geometry::Vec3{5, 6, 7}));
  s = run_ok(s, "G0 X0 Y0 Z0");
  BlockResult r = run(s, "G28 Z3");  // via Z3, then Z to the stored Z only
  ASSERT_TRUE(r.ok());
  ASSERT_EQ(r.actions.size(), 2u);
  EXPECT_EQ(std::get<LinearMove>(r.actions[1]).to, (geometry::Vec3{0, 0, 7}));
  r = run(s, "G28");
  ASSERT_EQ(r.actions.size(), 1u);
  EXPECT_EQ(r.state.position, (geometry::Vec3{5, 6, 7}));
}

TEST(Interpreter, ArcsRadiusAndCentre) {
  ParserState s = run_ok({}, "G1 X0 Y0 F100");
  BlockResult r = run(s, "G2 X10 Y0 R5");
  ASSERT_TRUE(r.ok());
  auto arc = std::get<ArcMove>(r.actions[0]);
  EXPECT_NEAR(arc.center.x, 5, 1e-9);
  EXPECT_NEAR(arc.center.y, 0, 1e-9);
  EXPECT_NEAR(arc_angular_travel(arc), -M_PI, 1e-9);
  // Full circle in centre format.
  r = run(s, "G3 X0 Y0 I5 J0");
  ASSERT_TRUE(r.ok());
  arc = std::get<ArcMove>(r.actions[0]);
  EXPECT_NEAR(arc_angular_travel(arc), 2 * M_PI, 1e-9);
  const auto pts = segment_arc(arc, 0.002);
  EXPECT_GT(pts.size(), 50u);
  for (const geometry::Vec3& p : pts) EXPECT_NEAR(std::hypot(p.x - 5, p.y), 5, 1e-9);
  // G18 arc: in the ZX plane the offsets are K and I.
  r = run(s, "G18 G2 X10 Z0 I5 K0");
  ASSERT_TRUE(r.ok());
  arc = std::get<ArcMove>(r.actions[0]);
  EXPECT_EQ(arc.plane, Plane::ZX);
  for (const geometry::Vec3& p : segment_arc(arc, 0.01)) {
    EXPECT_NEAR(std::hypot(p.x - 5, p.z), 5, 1e-9);
    EXPECT_NEAR(p.y, 0, 1e-12);
  }
  EXPECT_EQ(run(s, "G19 G2 Y10 Z0 J5").status, 0);
}

TEST(Interpreter, SpindleCoolantDwellProgramEnd) {
  BlockResult r = run({}, "M3 S1000 M8 G4 P0.5");
  ASSERT_TRUE(r.ok());
  bool spindle = false, coolant = false, dwell = false;
  for (const auto& a : r.actions) {
    if (auto* sp = std::get_if<SpindleChange>(&a)) spindle = sp->rpm == 1000 && sp->state == SpindleState::CW;
    if (auto* c = std::get_if<CoolantChange>(&a)) coolant = c->flood;
    if (auto* d = std::get_if<Dwell>(&a)) dwell = d->seconds == 0.5;
  }
  EXPECT_TRUE(spindle && coolant && dwell);
  ParserState s = run_ok(r.state, "G91 G55");
  r = run(s, "M30");
  ASSERT_TRUE(r.ok());
  EXPECT_FALSE(r.state.modal.incremental);
  EXPECT_EQ(r.state.modal.coord_select, 0);
  EXPECT_EQ(r.state.modal.spindle, SpindleState::Off);
  EXPECT_TRUE(std::holds_alternative<ProgramEnd>(r.actions.back()));
}

TEST(Interpreter, InverseTimeNeedsFEveryBlock) {
  ParserState s = run_ok({}, "G93 G1 X10 F2");  // 10 mm in 1/2 min -> 20 mm/min
  EXPECT_EQ(status_of("X20", s), 22);
  BlockResult r = run(s, "X20 F1");
  ASSERT_TRUE(r.ok());
  EXPECT_NEAR(std::get<LinearMove>(r.actions[0]).feed, 10, 1e-9);
}

TEST(Interpreter, InverseTimeArcTakesOneOverFMinutes) {
  ParserState s = run_ok({}, "G1 X0 Y0 F100");
  BlockResult r = run(s, "G2 X10 Y0 R5");
  ArcChords c = arc_chords(std::get<ArcMove>(r.actions[0]), 0.002);
  EXPECT_EQ(c.points.size(), segment_arc(std::get<ArcMove>(r.actions[0]), 0.002).size());
  EXPECT_NEAR(c.feed, 100, 1e-12);  // G94: the programmed feed
  r = run(s, "G93 G2 X10 Y0 R5 F2");  // half a circle in 1/2 min
  ASSERT_TRUE(r.ok());
  c = arc_chords(std::get<ArcMove>(r.actions[0]), 0.002);
  double length = 0;
  geometry::Vec3 p{0, 0, 0};
  for (const geometry::Vec3& q : c.points) {
    length += norm(q - p);
    p = q;
  }
  EXPECT_NEAR(length / c.feed, 0.5, 1e-12);
  EXPECT_LT(c.feed, 2 * 5 * M_PI);  // the chords are a hair shorter than the arc
  EXPECT_GT(c.feed, 2 * 5 * M_PI * 0.999);
}

TEST(Interpreter, JogRules) {
  ParserState s;
  BlockOptions jog{true};
  EXPECT_EQ(execute_block(s, "$J=X10", jog).status, 22);
  EXPECT_EQ(execute_block(s, "$J=G1X10F100", jog).status, 16);
  EXPECT_EQ(execute_block(s, "$J=M3X10F100", jog).status, 16);
  EXPECT_EQ(execute_block(s, "$J=X10F100S5", jog).status, 36);
  BlockResult r = execute_block(s, "$J=G91G20X1F10", jog);
  ASSERT_TRUE(r.ok());
  const auto& j = std::get<JogMove>(r.actions[0]);
  EXPECT_NEAR(j.to.x, 25.4, 1e-12);
  EXPECT_NEAR(j.feed, 254, 1e-9);
  EXPECT_FALSE(r.state.modal.incremental);  // jog modes do not stick
  EXPECT_TRUE(execute_block(s, "$J=G53X-5F100", jog).ok());
}
