#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "cncstream/protocol/line_cleaner.hpp"
#include "cncstream/protocol/response.hpp"

using namespace cncstream::protocol;

TEST(Response, Classifies) {
  EXPECT_EQ(parse_response("ok").kind, ResponseKind::Ok);
  auto e = parse_response("error:22");
  EXPECT_EQ(e.kind, ResponseKind::Error);
  EXPECT_EQ(e.code, 22);
  auto a = parse_response("ALARM:2");
  EXPECT_EQ(a.kind, ResponseKind::Alarm);
  EXPECT_EQ(a.code, 2);
  EXPECT_EQ(parse_response("[MSG:'$H'|'$X' to unlock]").kind, ResponseKind::Message);
  EXPECT_EQ(parse_response("[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]").kind, ResponseKind::ParserState);
  EXPECT_EQ(parse_response("[VER:1.1h.20190830:]").kind, ResponseKind::Version);
  EXPECT_EQ(parse_response("[OPT:V,15,128]").kind, ResponseKind::Options);
  EXPECT_EQ(parse_response("[G54:0.000,0.000,0.000]").kind, ResponseKind::Feedback);
  EXPECT_EQ(parse_response(">G54G20:ok").kind, ResponseKind::StartupEcho);
  const auto failed = parse_response(">G1X1:error:22");
  EXPECT_EQ(failed.kind, ResponseKind::StartupEcho);
  EXPECT_EQ(failed.body, "G1X1");
  EXPECT_EQ(failed.code, 22);
  EXPECT_EQ(parse_response("Grbl 1.1h ['$' for help]").kind, ResponseKind::Other);
  auto rs = parse_response("Resend: 42");
  EXPECT_EQ(rs.kind, ResponseKind::Resend);
  EXPECT_EQ(rs.code, 42);
  EXPECT_EQ(parse_response("Error:checksum mismatch, Last Line: 41").kind, ResponseKind::MarlinError);
  EXPECT_EQ(parse_response("echo:busy: processing").kind, ResponseKind::Busy);
  auto ok = parse_response("ok N10 P15 B3");
  EXPECT_EQ(ok.kind, ResponseKind::Ok);
  EXPECT_EQ(*ok.ok_line, 10);
  EXPECT_EQ(*ok.ok_planner_free, 15);
  EXPECT_EQ(*ok.ok_buffer_free, 3);
  EXPECT_FALSE(parse_response("error:x").parse_error.empty());
}

TEST(BuildOptions, ReadsBlocksAndRx) {
  auto o = parse_build_options("VNMSL,35,1024,3,0");
  ASSERT_TRUE(o);
  EXPECT_EQ(*o->planner_blocks, 35);
  EXPECT_EQ(*o->rx_buffer_size, 1024);
  EXPECT_FALSE(parse_build_options("V,abc,128"));
  EXPECT_FALSE(parse_build_options("V")->rx_buffer_size);
}

TEST(Status, EveryFieldAnyOrder) {
  const std::vector<std::string> fields = {"MPos:1.000,2.000,-3.500", "Bf:15,128", "FS:500,12000", "WCO:0.5,1,2",
                                           "Ov:100,50,120", "Pn:XYZPDHRS", "A:SFM", "Ln:99"};
  std::mt19937 rng(7);
  for (int round = 0; round < 20; ++round) {
    auto f = fields;
    std::shuffle(f.begin(), f.end(), rng);
    std::string line = "<Hold:1";
    for (const auto& x : f) line += "|" + x;
    line += ">";
    std::string err;
    auto r = parse_status_report(line, &err);
    ASSERT_TRUE(r) << line << ": " << err;
    EXPECT_EQ(r->state, MachineState::Hold);
    EXPECT_EQ(r->substate, 1);
    EXPECT_DOUBLE_EQ((*r->mpos)[2], -3.5);
    EXPECT_EQ(*r->planner_free, 15);
    EXPECT_EQ(*r->rx_free, 128);
    EXPECT_DOUBLE_EQ(*r->feed, 500);
    EXPECT_DOUBLE_EQ(*r->spindle, 12000);
    EXPECT_DOUBLE_EQ((*r->wco)[1], 1);
    EXPECT_EQ((*r->overrides)[1], 50);
    EXPECT_EQ(*r->pins, "XYZPDHRS");
    EXPECT_EQ(*r->accessories, "SFM");
    EXPECT_EQ(*r->line_number, 99);
  }
}

TEST(Status, StatesAndMissingFields) {
  for (const char* s : {"Idle", "Run", "Hold:0", "Jog", "Alarm", "Door:2", "Check", "Home", "Sleep", "Tool"}) {
    auto r = parse_status_report(std::string("<") + s + "|WPos:0,0,0>");
    ASSERT_TRUE(r) << s;
    EXPECT_FALSE(r->mpos);
    EXPECT_TRUE(r->wpos);
  }
  auto r = parse_status_report("<Idle|MPos:0,0,0|F:300|MPG:1|H:1,7>");
  ASSERT_TRUE(r);
  EXPECT_TRUE(*r->mpg);
  EXPECT_DOUBLE_EQ(*r->feed, 300);
  EXPECT_FALSE(parse_status_report("<Flying|MPos:0,0,0>"));
  EXPECT_FALSE(parse_status_report("<Idle|MPos:0,x,0>"));
  EXPECT_FALSE(parse_status_report("<Idle|MPos:0,0,0"));
}

TEST(Status, TrackerComputesWposFromLastWco) {
  StatusTracker t;
  t.update(*parse_status_report("<Idle|MPos:10,20,30|WCO:1,2,3|Ov:100,100,100>"));
  auto r = t.update(*parse_status_report("<Run|MPos:11,22,33|FS:100,0>"));
  EXPECT_DOUBLE_EQ((*r.wpos)[0], 10);
  EXPECT_DOUBLE_EQ((*r.wpos)[1], 20);
  EXPECT_DOUBLE_EQ((*r.wpos)[2], 30);
  EXPECT_TRUE(r.overrides);
  r = t.update(*parse_status_report("<Run|WPos:0,0,0>"));
  EXPECT_DOUBLE_EQ((*r.mpos)[2], 3);
}

TEST(Cleaner, StripsCommentsAndSpaces) {
  EXPECT_EQ(*clean_gcode_line("G1 X1.5 (move) Y2 ; done"), "G1X1.5Y2");
  EXPECT_EQ(*clean_gcode_line("  %  "), "");
  EXPECT_FALSE(clean_gcode_line("G1 (oops"));
  CleanOptions keep;
  keep.strip_whitespace = false;
  EXPECT_EQ(*clean_gcode_line("M117 Hello world ; c", keep), "M117 Hello world");
}

TEST(Cleaner, PersistentWrites) {
  for (const char* s : {"$100=250", "$N0=G20", "$I=plate", "$RST=*", "G10L2P1X0", "G10L20P1X0Y0", "G28.1", "G30.1"})
    EXPECT_TRUE(is_persistent_write(s)) << s;
  for (const char* s : {"$J=G91X1F100", "$H", "$X", "G10L1P1", "G28", "G1X10", "$$", "$#"})
    EXPECT_FALSE(is_persistent_write(s)) << s;
}

TEST(Cleaner, LongLineIsRejectedBeforeSendingWithFileLine) {
  // The long line appended, not `+`: GCC 12 at -O3 warns falsely (-Warray-bounds) on the latter.
  std::string long_line = "G1 X";
  long_line.append(90, '1');
  std::vector<std::string> lines = {"G21", "G1 X1 (short)", long_line};
  auto p = prepare_program(lines, "part.nc", 80);
  ASSERT_EQ(p.errors.size(), 1u);
  EXPECT_NE(p.errors[0].find("part.nc:3:"), std::string::npos) << p.errors[0];
  auto q = prepare_program({"G1 X1 ? Y2"}, "part.nc", 80);
  EXPECT_EQ(q.errors.size(), 1u);
}
