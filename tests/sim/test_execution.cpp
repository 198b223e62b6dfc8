// The simulator's account of what it carried out (lines_executed and the
// line observer) and its wire faults at a point: the instruments the soak
// uses to prove that no line was lost or repeated.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "cncsim/machine.hpp"
#include "sim_test_util.hpp"

using namespace cncsim;
using simtest::lines_of;
using simtest::send;

namespace {

struct Recorder {
  std::vector<long> n;  // N words in the order their lines ran
  void attach(Machine& m) {
    m.set_line_observer([this](const ExecutedLine& l) { n.push_back(l.n); });
  }
};

Machine fast_machine(Faults f = {}) {
  MachineOptions o;
  o.instant_waits = true;
  o.faults = std::move(f);
  Machine m(o);
  m.take_output();
  return m;
}

std::string numbered_move(int n) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "N%d G1 X%d Y%d F3000", n, n % 7, n % 5);
  return buf;
}

// "N<n> X<x>\n"
std::string numbered_x(int n, int x) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "N%d X%d\n", n, x);
  return buf;
}

// Sends lines with GRBL character counting until all are answered.
std::vector<std::string> stream(Machine& m, const std::vector<std::string>& lines) {
  std::vector<std::string> answers;
  std::size_t next = 0, used = 0;
  std::vector<std::size_t> costs;
  std::string pending;
  for (int guard = 0; guard < 100000 && answers.size() < lines.size(); ++guard) {
    while (next < lines.size() && used + lines[next].size() + 1 <= 127) {
      m.receive(lines[next] + "\n");
      costs.push_back(lines[next].size() + 1);
      used += costs.back();
      ++next;
    }
    m.advance(0.01);
    pending += m.take_output();
    const auto nl = pending.rfind('\n');
    if (nl == std::string::npos) continue;
    for (const auto& l : lines_of(pending.substr(0, nl + 1)))
      if (l == "ok" || l.rfind("error:", 0) == 0) {
        answers.push_back(l);
        used -= costs[answers.size() - 1];
      }
    pending.erase(0, nl + 1);
  }
  return answers;
}

}  // namespace

TEST(Execution, EveryLineOfAProgramRunsOnceInOrder) {
  Machine m = fast_machine();
  Recorder r;
  r.attach(m);
  std::vector<std::string> prog{"N1 G21 G90 G94", "N2 G0 Z1"};
  for (int n = 3; n <= 60; ++n) prog.push_back(numbered_move(n));
  prog.push_back("N61 G4 P0.01");
  prog.push_back("N62 M2");
  const auto answers = stream(m, prog);
  m.run_until_idle();
  ASSERT_EQ(answers.size(), prog.size());
  EXPECT_EQ(m.lines_executed(), prog.size());
  ASSERT_EQ(r.n.size(), prog.size());
  for (std::size_t i = 0; i < r.n.size(); ++i) EXPECT_EQ(r.n[i], static_cast<long>(i) + 1);
}

TEST(Execution, AMoveStillInThePlannerHasNotRun) {
  Machine m = fast_machine();
  send(m, "G21 G90 G1 F100");  // slow moves: the planner fills before they run
  const std::size_t before = m.lines_executed();
  for (int n = 1; n <= 5; ++n) m.receive(numbered_x(n, n * 10));
  m.advance(0.001);
  // Answered (planned), but not carried out yet.
  EXPECT_EQ(m.lines_answered(), 6u);
  EXPECT_EQ(m.lines_executed(), before);
  m.run_until_idle();
  EXPECT_EQ(m.lines_executed(), before + 5);
}

TEST(Execution, AnAlarmDropsThePlannedLinesAndAnErrorRunsNothing) {
  Faults f;
  f.error_at[3] = 20;  // received line 3: answered error:20 instead of running
  f.alarm_at[9] = 3;   // received line 9 raises ALARM:3: the planner is dropped
  MachineOptions o;  // real waits: moves stay in the planner while lines arrive
  o.faults = f;
  Machine m(o);
  m.take_output();
  Recorder r;
  r.attach(m);
  send(m, "G21 G90 G1 F60");  // received line 1
  for (int n = 2; n <= 9; ++n) m.receive(numbered_x(n, n));
  m.advance(0.01);
  const std::string out = m.take_output();
  EXPECT_NE(out.find("error:20"), std::string::npos) << out;
  EXPECT_NE(out.find("ALARM:3"), std::string::npos) << out;
  m.run_until_idle();
  // Line 1 ran (modes only); N3 was refused; N2 and N4..N8 were planned but
  // the alarm dropped them before they ran (1 mm at 1 mm/s each); N9 came
  // with the alarm and was refused (error:9).
  EXPECT_EQ(m.lines_executed(), 1u);
  EXPECT_EQ(r.n, std::vector<long>{0});
  EXPECT_EQ(m.faults_applied().errors, 1u);
  EXPECT_EQ(m.faults_applied().alarms, 1u);
}

TEST(Execution, CheckModeRunsNothing) {
  Machine m = fast_machine();
  send(m, "$C");
  const std::size_t before = m.lines_executed();
  send(m, "N1 G1 X5 F100");
  send(m, "N2 G0 Z3");
  EXPECT_EQ(m.lines_executed(), before);
}

TEST(Execution, WireFaultsAtAPointDamageOneLineOnce) {
  Faults f;
  f.drop_byte_at[2] = ByteOfLine::at(3);            // "N2 G1..." loses its 4th byte ('G')
  f.corrupt_byte_at[3] = ByteOfLine::at(1);         // "N3..." -> "N2...": the number itself
  f.drop_byte_at[4] = ByteOfLine::end_of_line();    // N4 and N5 merge: one line, a repeated N word
  // From here a received line is one file line ahead: N4 and N5 came as one.
  f.drop_byte_at[5] = ByteOfLine::first('Q');       // N6 has no Q: left alone
  f.corrupt_byte_at[6] = ByteOfLine::first('X');    // N7's X -> Y: a repeated word
  Machine m = fast_machine(f);
  Recorder r;
  r.attach(m);
  std::vector<std::string> prog;
  for (int n = 1; n <= 7; ++n) prog.push_back(numbered_move(n));
  m.receive("?");  // real-time bytes are no part of a line: no offset moves
  for (const auto& l : prog) m.receive(l.substr(0, 2) + "?" + l.substr(2) + "\n");
  m.run_until_idle();
  const auto answers = [&] {
    std::vector<std::string> a;
    for (const auto& l : lines_of(m.take_output()))
      if (l == "ok" || l.rfind("error:", 0) == 0) a.push_back(l);
    return a;
  }();
  ASSERT_EQ(answers.size(), 6u) << "one answer per line as the firmware saw them";
  EXPECT_EQ(answers[3], "error:25") << "merged N4N5: repeated word";
  EXPECT_EQ(answers[5], "error:25") << "N7 with two Y words";
  EXPECT_EQ(m.faults_applied().dropped_bytes, 2u);
  EXPECT_EQ(m.faults_applied().corrupted_bytes, 2u);
  // Damage the firmware cannot see runs, as on a real GRBL (no checksum):
  // N2 lost its G and ran as N21, N3's number became N2.
  EXPECT_EQ(r.n, (std::vector<long>{1, 21, 2, 6}));
  EXPECT_EQ(m.faults().drop_byte_at.size(), 1u) << "N6's fault found no Q and waits";
  EXPECT_TRUE(m.faults().corrupt_byte_at.empty());
  EXPECT_EQ(m.lines_received(), 6u);
}

TEST(Execution, StartsWhereASavedStateLeftTheTool) {
  MachineOptions o;
  o.start_position = cncstream::geometry::Vec3{-10, -20, -3};
  Machine m(o);
  m.take_output();
  EXPECT_EQ(m.status_report().rfind("<Idle|MPos:-10.000,-20.000,-3.000|", 0), 0u);
  send(m, "G91 G0 X1");
  m.run_until_idle();
  EXPECT_NEAR(m.machine_position().x, -9, 1e-9);
  EXPECT_NEAR(m.machine_position().y, -20, 1e-9);
}

// A feed hold at any moment of a job comes to rest (Hold:0): a streamer
// waits for it before a controlled stop or a resume. The soak once found
// the simulator in Hold:1 for ever with nothing left in its planner.
TEST(Execution, AFeedHoldAtAnyMomentComesToRest) {
  int stuck = 0;
  std::string example;
  for (int i = 0; i < 600; ++i) {
    MachineOptions o;
    Machine m(o);
    m.take_output();
    m.receive("G21 G90 G1 F2400\n");
    for (int k = 1; k <= 6; ++k) m.receive(numbered_move(k) + "\n");
    m.receive("N7 G2 X7 Y2 I1 J0\n");
    m.advance(0.05 + i * 0.0075);
    m.receive("!");
    for (int k = 0; k < 200 && m.state_name() != "Hold:0" && m.state() == MachineState::Hold; ++k) m.advance(0.05);
    if (m.state() == MachineState::Hold && m.state_name() != "Hold:0") {
      ++stuck;
      example = m.status_report() + " planner " + std::to_string(m.planner_blocks());
    }
  }
  EXPECT_EQ(stuck, 0) << example;
}
