// A program of several operations: one header, a tool change (spindle off,
// retract, the operator's note, T, M0) between tools and none between
// operations of one tool, the spindle back on after it; and what a streamer
// reads back as the pause's note.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "cncstream/gcode/interpreter.hpp"
#include "cncstream/gcode/job_program.hpp"
#include "cncstream/gcode/line_lexer.hpp"
#include "cncstream/gcode/program_pause.hpp"

using namespace cncstream;

namespace {

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::size_t from = 0;
  while (from < text.size()) {
    const std::size_t nl = text.find('\n', from);
    out.push_back(text.substr(from, nl - from));
    if (nl == std::string::npos) break;
    from = nl + 1;
  }
  return out;
}

std::size_t index_of(const std::vector<std::string>& lines, const std::string& line, std::size_t from = 0) {
  for (std::size_t i = from; i < lines.size(); ++i)
    if (lines[i] == line) return i;
  return lines.size();
}

std::vector<cam::Polyline> square(double z) {
  return {{{0, 0, z}, {10, 0, z}, {10, 10, z}, {0, 10, z}, {0, 0, z}}};
}

MachiningParams feeds() {
  MachiningParams mp;
  mp.feed = 1200;
  mp.plunge_feed = 300;
  mp.safe_z = 8;
  return mp;
}

}  // namespace

TEST(JobProgram, ToolChangeBetweenTwoToolsPausesWithTheOperatorsNote) {
  JobProgramOptions o;
  o.safe_z = 8;
  o.header_comments = {"two tools"};
  JobProgram p(o);
  p.begin_operation({"roughing", 1, cam::Cutter::flat(6), 16000});
  write_pieces(p.writer(), square(-2), {}, feeds(), p.stats());
  p.begin_operation({"finishing", 2, cam::Cutter::ball(3.175), 18000});
  write_pieces(p.writer(), square(-3), {}, feeds(), p.stats());
  const std::string text = p.finish();
  const auto lines = lines_of(text);

  EXPECT_EQ(std::count(lines.begin(), lines.end(), "G21 G90 G17 G94"), 2);  // the header, again after the pause
  const std::size_t t1 = index_of(lines, "T1"), t2 = index_of(lines, "T2"), m0 = index_of(lines, "M0");
  ASSERT_LT(t1, lines.size());
  ASSERT_LT(t2, lines.size());
  ASSERT_LT(m0, lines.size());
  EXPECT_EQ(m0, t2 + 1);
  // At the pause: spindle off and the tool at the safe Z.
  EXPECT_LT(index_of(lines, "M5", t1), t2);
  gcode::ParserState state;
  for (std::size_t i = 0; i < m0; ++i) {
    const std::string cleaned = gcode::clean_line(lines[i]).text;
    if (cleaned.empty()) continue;
    const auto r = gcode::execute_block(state, cleaned);
    ASSERT_TRUE(r.ok()) << lines[i];
    state = r.state;
  }
  EXPECT_DOUBLE_EQ(state.position.z, 8);
  EXPECT_EQ(state.modal.spindle, gcode::SpindleState::Off);
  // After it: spindle on with the finishing speed before any cut.
  const std::size_t m3 = index_of(lines, "M3 S18000", m0);
  ASSERT_LT(m3, lines.size());
  for (std::size_t i = m0; i < m3; ++i) EXPECT_EQ(lines[i].rfind("G1", 0), std::string::npos) << lines[i];
  EXPECT_EQ(lines.back(), "M2");

  // The note a streamer shows at the pause names the tool to mount.
  const auto note = gcode::program_pause_note(lines, m0);
  ASSERT_TRUE(note);
  EXPECT_NE(note->find("mount T2"), std::string::npos) << *note;
  EXPECT_NE(note->find("ball:3.175"), std::string::npos) << *note;
  EXPECT_FALSE(gcode::program_pause_note(lines, t2));

  // M6 instead of M0 where the controller has one.
  o.tool_change = ToolChangeCode::M6;
  JobProgram q(o);
  q.begin_operation({"roughing", 1, cam::Cutter::flat(6), 16000});
  write_pieces(q.writer(), square(-2), {}, feeds(), q.stats());
  q.begin_operation({"finishing", 2, cam::Cutter::ball(3.175), 18000});
  write_pieces(q.writer(), square(-3), {}, feeds(), q.stats());
  const auto m6_lines = lines_of(q.finish());
  EXPECT_EQ(index_of(m6_lines, "M0"), m6_lines.size());
  EXPECT_EQ(index_of(m6_lines, "M6"), index_of(m6_lines, "T2") + 1);
}

TEST(JobProgram, SameToolGoesOnWithoutAPauseAndTheProgramRuns) {
  JobProgramOptions o;
  o.safe_z = 8;
  JobProgram p(o);
  p.begin_operation({"roughing", 1, cam::Cutter::ball(3), 18000});
  write_pieces(p.writer(), square(-2), {}, feeds(), p.stats());
  p.begin_operation({"finishing", 1, cam::Cutter::ball(3), 18000});
  write_pieces(p.writer(), square(-3), {}, feeds(), p.stats());
  const std::string text = p.finish();
  const auto lines = lines_of(text);
  EXPECT_EQ(index_of(lines, "M0"), lines.size());
  EXPECT_EQ(std::count(lines.begin(), lines.end(), "T1"), 1);
  EXPECT_EQ(std::count(lines.begin(), lines.end(), "M3 S18000"), 1);
  EXPECT_EQ(p.stats().lines, lines.size());
  EXPECT_NEAR(p.stats().cut_length, 2 * 40.0 + 10 + 11, 1e-9);  // two squares, plunges from Z8

  // Every line is G-code GRBL takes, and the cuts reach both depths.
  gcode::ParserState state;
  double lowest = 0;
  for (const auto& l : lines) {
    const std::string cleaned = gcode::clean_line(l).text;
    if (cleaned.empty()) continue;
    const auto r = gcode::execute_block(state, cleaned);
    ASSERT_TRUE(r.ok()) << l << ": error " << r.status;
    state = r.state;
    lowest = std::min(lowest, state.position.z);
  }
  EXPECT_DOUBLE_EQ(lowest, -3);
}

TEST(JobProgram, RefusesAnEmptyProgramAndABadToolNumber) {
  JobProgram p(JobProgramOptions{});
  EXPECT_THROW(p.finish(), std::invalid_argument);
  EXPECT_THROW(p.begin_operation({"x", 0, cam::Cutter::flat(6), 1000}), std::invalid_argument);
}

TEST(ProgramPause, M0WordsAndNotes) {
  EXPECT_TRUE(gcode::is_program_pause("M0"));
  EXPECT_TRUE(gcode::is_program_pause("m00 (wait)"));
  EXPECT_TRUE(gcode::is_program_pause("G0 Z5 M0"));
  EXPECT_FALSE(gcode::is_program_pause("M01"));
  EXPECT_FALSE(gcode::is_program_pause("M05"));
  EXPECT_FALSE(gcode::is_program_pause("M30"));
  EXPECT_FALSE(gcode::is_program_pause("(M0 in a comment)"));
  EXPECT_FALSE(gcode::is_program_pause("; M0"));
  const std::vector<std::string> lines = {"G1 X1", "(mount the 6 mm flat)", "(then touch off)", "T3", "M0", "M0"};
  EXPECT_EQ(gcode::program_pause_note(lines, 4).value_or("?"), "mount the 6 mm flat then touch off");
  EXPECT_EQ(gcode::program_pause_note(lines, 5).value_or("?"), "");  // a pause right after a pause: no note of its own
  EXPECT_FALSE(gcode::program_pause_note(lines, 0));
  EXPECT_FALSE(gcode::program_pause_note(lines, 9));
}

TEST(JobProgram, OperationsAndTheToolInTheSpindleAreReadBackFromTheLines) {
  JobProgramOptions o;
  o.safe_z = 8;
  JobProgram p(o);
  // A long name wraps its comment over two lines; a bull-nose's description
  // has commas of its own.
  p.begin_operation({"roughing", 1, cam::Cutter::bull(6, 1), 16000});
  write_pieces(p.writer(), square(-2), {}, feeds(), p.stats());
  p.begin_operation({"rest roughing along the steepest walls of the part", 2, cam::Cutter::ball(3.175), 18000});
  write_pieces(p.writer(), square(-3), {}, feeds(), p.stats());
  p.begin_operation({"finishing", 2, cam::Cutter::ball(3.175), 18000});
  write_pieces(p.writer(), square(-3.5), {}, feeds(), p.stats());
  const auto lines = lines_of(p.finish());

  const auto ops = program_operations(lines);
  ASSERT_EQ(ops.size(), 3u);
  EXPECT_EQ(ops[0].number, 1);
  EXPECT_EQ(ops[0].name, "roughing");
  EXPECT_EQ(ops[0].tool, 1);
  EXPECT_EQ(ops[0].cutter, cam::Cutter::bull(6, 1).description() + " [" + cam::Cutter::bull(6, 1).spec() + "]");
  EXPECT_EQ(ops[1].name, "rest roughing along the steepest walls of the part");
  EXPECT_EQ(ops[1].tool, 2);
  EXPECT_EQ(ops[1].cutter, "3.175 mm ball-nose end mill [ball:3.175]");
  EXPECT_EQ(ops[2].name, "finishing");
  // Lines are 1-based: the comment, and the pause of the tool change.
  EXPECT_EQ(lines[ops[0].first_line - 1].rfind("(operation 1: roughing with T1", 0), 0u);
  EXPECT_EQ(ops[0].mounted_line, ops[0].first_line);
  EXPECT_EQ(lines[ops[1].mounted_line - 1], "M0");
  EXPECT_GT(ops[1].mounted_line, ops[1].first_line);
  EXPECT_EQ(ops[2].mounted_line, ops[2].first_line);  // the same tool goes on: no pause

  // Up to the pause T1 is in; from it on T2, in either of its operations.
  EXPECT_EQ(operation_after_line(ops, 0)->number, 1);
  EXPECT_EQ(operation_after_line(ops, ops[1].mounted_line - 1)->number, 1);
  EXPECT_EQ(operation_after_line(ops, ops[1].mounted_line)->number, 2);
  EXPECT_EQ(operation_after_line(ops, ops[2].first_line)->number, 3);
  EXPECT_EQ(operation_after_line(ops, lines.size())->tool, 2);
  EXPECT_FALSE(operation_after_line(program_operations({"G0 X1", "(operation x: not ours)"}), 1));
}
