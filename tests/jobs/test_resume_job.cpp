// Resume planning on a small program with known answers: the line chosen from
// the journaled status report or by backing off, the operator's line, the
// preamble and what follows it, and the travel height.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "cncsim/machine.hpp"
#include "cncstream/gcode/program.hpp"
#include "cncstream/gcode/resume.hpp"
#include "cncstream/jobs/resume_job.hpp"

using namespace cncstream;

namespace {

// A square at Z-1 with the spindle on: line 7 cuts from (10, 0) to (10, 10).
const std::vector<std::string> kProgram = {
    "G21 G90 G94 G17",  // 1
    "G0 Z5",            // 2
    "M3 S12000",        // 3
    "G0 X0 Y0",         // 4
    "G1 Z-1 F300",      // 5
    "G1 X10 F800",      // 6
    "G1 Y10",           // 7
    "G1 X0",            // 8
    "G0 Z5",            // 9
    "M5",               // 10
    "M2",               // 11
};

jobs::ResumeInput input() {
  jobs::ResumeInput in;
  in.file = "square.nc";
  in.file_sha256 = "abc";
  in.lines = kProgram;
  in.last_line = 8;
  return in;
}

}  // namespace

TEST(ResumeJob, StatusReportPicksTheLineBeingCut) {
  jobs::ResumeInput in = input();
  in.status_work_pos = geometry::Vec3{10, 5, -1};  // half-way along line 7
  in.status_line = 8;
  const jobs::ResumePlan plan = jobs::plan_resume(in);
  EXPECT_EQ(plan.from_line, 6);
  EXPECT_EQ(plan.reason, "the controller last reported the tool at X10 Y5 Z-1, on line 7");
  EXPECT_EQ(plan.total_lines, 11);
  EXPECT_EQ(plan.file, "square.nc");
  EXPECT_EQ(plan.file_sha256, "abc");
  // The state after line 6: at (10, 0, -1), spindle on, G1 at F800.
  const geometry::Vec3 p = plan.state.work_position();
  EXPECT_EQ(p.x, 10);
  EXPECT_EQ(p.y, 0);
  EXPECT_EQ(p.z, -1);
  // Travel at the program's highest point, then spindle, dwell, plunge.
  EXPECT_EQ(plan.options.safe_z, 5);
  const std::vector<std::string> head = {"G21 G90 G94 G17", "G54", "G92.1", "G49", "G0 Z5", "G0 X10 Y0",
                                         "M3 S12000", "M9", "G4 P2", "G1 Z-1 F300"};
  ASSERT_GE(plan.preamble.size(), head.size());
  EXPECT_EQ(std::vector<std::string>(plan.preamble.begin(), plan.preamble.begin() + long(head.size())), head);
  // Preamble, then the file from line 7, each with its file line.
  ASSERT_EQ(plan.lines.size(), plan.preamble.size() + 5);
  ASSERT_EQ(plan.source_lines.size(), plan.lines.size());
  for (std::size_t k = 0; k < plan.preamble.size(); ++k) {
    EXPECT_EQ(plan.lines[k], plan.preamble[k]);
    EXPECT_EQ(plan.source_lines[k], 6);
  }
  for (std::size_t k = 0; k < 5; ++k) {
    EXPECT_EQ(plan.lines[plan.preamble.size() + k], kProgram[6 + k]);
    EXPECT_EQ(plan.source_lines[plan.preamble.size() + k], long(7 + k));
  }
  // After the plunge, the program's own modes and feed again.
  const std::vector<std::string> tail = {"G21 G90 G17 G94", "F800", "G1"};
  ASSERT_EQ(plan.preamble.size(), head.size() + tail.size());
  EXPECT_EQ(std::vector<std::string>(plan.preamble.begin() + long(head.size()), plan.preamble.end()), tail);
}

TEST(ResumeJob, WithoutAStatusReportBacksOffThePlannerQueue) {
  const jobs::ResumePlan plan = jobs::plan_resume(input());
  // The five motion lines before line 8 may all have been queued unmade: back
  // to the first of them (line 2), continuing after line 1.
  EXPECT_EQ(plan.from_line, 1);
  EXPECT_EQ(plan.reason,
            "no position report was journaled; backing off 5 motion lines from the last answered one (the planner "
            "may have held them unmade)");
  EXPECT_EQ(plan.lines.size(), plan.preamble.size() + 10);
}

TEST(ResumeJob, OperatorsLineAndTravelHeight) {
  jobs::ResumeInput in = input();
  in.from_line = 7;
  in.safe_z = 12;
  in.machine_safe_z = -2;
  in.plunge_feed = 150;
  in.dwell_s = 0;
  const jobs::ResumePlan plan = jobs::plan_resume(in);
  EXPECT_EQ(plan.from_line, 7);
  EXPECT_EQ(plan.reason, "--from-line");
  EXPECT_EQ(plan.options.safe_z, 12);
  const std::vector<std::string> head = {"G21 G90 G94 G17", "G53 G0 Z-2", "G54", "G92.1", "G49", "G0 Z12",
                                         "G0 X10 Y10", "M3 S12000", "M9", "G1 Z-1 F150"};
  ASSERT_GE(plan.preamble.size(), head.size());
  EXPECT_EQ(std::vector<std::string>(plan.preamble.begin(), plan.preamble.begin() + long(head.size())), head);
  EXPECT_EQ(plan.lines.back(), "M2");
}

TEST(ResumeJob, NothingLeftAfterTheLastLine) {
  jobs::ResumeInput in = input();
  in.from_line = 11;
  try {
    jobs::plan_resume(in);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "--from-line 11: square.nc has only 11 lines; nothing left to run");
  }
}

// GRBL answers a bare "G2"/"G3" with error:26, so a resume after an arc line
// used to fail in its preamble, every time (found by the soak). The preamble
// leaves the arc mode out and the first line moving in it names it.
TEST(ResumeJob, AfterAnArcTheFirstLineMovingInTheModalArcNamesIt) {
  const std::vector<std::string> prog = {
      "G21 G90 G94 G17",       // 1
      "G0 Z5",                 // 2
      "G0 X0 Y0",              // 3
      "G1 Z-1 F300",           // 4
      "G2 X10 Y0 I5 J0 F600",  // 5: half circle
      "X0 Y0 I-5 J0",          // 6: the modal G2 back
      "G92 X0",                // 7: axis words, but no motion
      "X10 Y0 I5 J0",          // 8: G2 again, still modal
      "G1 X20",                // 9
      "G0 Z5",                 // 10
      "M2",                    // 11
  };
  auto run = [](const std::vector<std::string>& lines) {
    cncsim::MachineOptions o;
    o.instant_waits = true;
    cncsim::Machine m(o);
    m.take_output();
    std::string errors;
    for (const auto& l : lines) {
      m.receive(l + "\n");
      m.run_until_idle();
      const std::string out = m.take_output();
      if (out.find("ok") == std::string::npos) errors += l + " -> " + out;
    }
    return std::make_pair(m.work_position(), errors);
  };
  const auto straight = run(prog);
  ASSERT_EQ(straight.second, "");
  for (long n : {5L, 6L, 7L}) {
    SCOPED_TRACE("resume after line " + std::to_string(n));
    jobs::ResumeInput in;
    in.file = "arcs.nc";
    in.lines = prog;
    in.from_line = n;
    in.dwell_s = 0;
    const jobs::ResumePlan plan = jobs::plan_resume(in);
    for (const auto& l : plan.preamble) {
      EXPECT_NE(l, "G2");
      EXPECT_NE(l, "G3");
    }
    const std::string first = plan.lines[plan.preamble.size()];
    const std::string expected_first = n == 5 ? "G2 X0 Y0 I-5 J0" : n == 6 ? "G92 X0" : "G2 X10 Y0 I5 J0";
    EXPECT_EQ(first, expected_first);
    // G92's axis words move nothing: line 8 still relies on the modal G2.
    if (n == 6) {
      EXPECT_EQ(plan.lines[plan.preamble.size() + 1], "G2 X10 Y0 I5 J0");
    }
    // A fresh controller takes every line and ends where the straight run did.
    const auto resumed = run(plan.lines);
    EXPECT_EQ(resumed.second, "");
    EXPECT_NEAR(resumed.first.x, straight.first.x, 1e-9);
    EXPECT_NEAR(resumed.first.z, straight.first.z, 1e-9);
  }
}

// A resume killed in its preamble, before it journaled a progress row, used
// to restart the whole program (no last line: "no motion before the last
// answered line", line 0). Nothing past its own resume line ran, so that
// line is where to continue again.
TEST(ResumeJob, AResumeThatRanNoFileLineContinuesWhereItWasToContinue) {
  jobs::ResumeInput in = input();
  in.last_line = 0;  // no progress row at all
  in.resumed_after = 6;
  jobs::ResumePlan plan = jobs::plan_resume(in);
  EXPECT_EQ(plan.from_line, 6);
  EXPECT_NE(plan.reason.find("resumed after line 6"), std::string::npos) << plan.reason;
  in.last_line = 6;  // only its preamble was answered (journaled as line 6)
  in.status_work_pos = geometry::Vec3{3, 3, 5};  // travelling above the part
  in.status_line = 6;
  EXPECT_EQ(jobs::plan_resume(in).from_line, 6);
  in.last_line = 7;  // it ran on: the usual choice
  in.status_work_pos = geometry::Vec3{10, 5, -1};
  in.status_line = 7;
  EXPECT_EQ(jobs::plan_resume(in).from_line, 6);
  EXPECT_EQ(jobs::plan_resume(in).reason, "the controller last reported the tool at X10 Y5 Z-1, on line 7");
}

// The lines the controller may not have run reach back one planner queue
// from the last report, and further for every error answer (up to three
// program lines that took no planner block, see ResumeInput). The window
// used to be 16 motion lines whatever the controller (grblHAL plans 35) and
// whatever the errors: the soak found resumes after an error that skipped a
// line that never ran.
TEST(ResumeJob, TheWindowCoversThePlannerAndTheLinesAnsweredWithAnError) {
  std::vector<std::string> prog = {"G21 G90 G94", "G0 Z1", "G1 Z-1 F300"};
  for (int k = 4; k <= 63; ++k) prog.push_back("G1 X" + std::to_string(k - 3) + " F800");  // line k ends at X(k-3)
  jobs::ResumeInput in;
  in.file = "row.nc";
  in.lines = prog;
  in.last_line = 63;
  in.planner_blocks = 15;
  EXPECT_EQ(jobs::plan_resume(in).from_line, 47) << "no report: back off 16 motion lines";
  in.error_lines = {10};  // long before: the job went on after it
  EXPECT_EQ(jobs::plan_resume(in).from_line, 44) << "one error: three more";
  in.error_lines = {};
  in.planner_blocks = 0;
  EXPECT_EQ(jobs::plan_resume(in).from_line, 27) << "planner unknown: grblHAL's 35 + 1";
  // The last report put the tool on line 46, 18 motion lines back.
  in.planner_blocks = 15;
  in.status_work_pos = geometry::Vec3{42.5, 0, -1};
  in.status_line = 63;
  in.error_lines = {10};
  const auto plan = jobs::plan_resume(in);
  EXPECT_EQ(plan.from_line, 45);
  EXPECT_EQ(plan.reason, "the controller last reported the tool at X42.5 Y0 Z-1, on line 46");
  in.error_lines = {};  // a window too short for it backs off from the last answered line instead
  EXPECT_EQ(jobs::plan_resume(in).from_line, 47);
  // The machine went on past a line that failed: it runs again.
  in.status_work_pos = geometry::Vec3{52.5, 0, -1};  // on line 56
  in.error_lines = {53};
  const auto past = jobs::plan_resume(in);
  EXPECT_EQ(past.from_line, 52);
  EXPECT_EQ(past.reason, "the controller last reported the tool at X52.5 Y0 Z-1, on line 56; line 53 was answered "
                         "with an error and never ran: it runs again");
}

TEST(ResumeJob, AJobProgramsPlanNamesTheOperationAndTheToolItGoesOnWith) {
  // Two operations, a tool change between them (as JobProgram writes it).
  jobs::ResumeInput in;
  in.file = "job.nc";
  in.file_sha256 = "abc";
  in.lines = {
      "G21 G90 G17 G94",                                            // 1
      "(operation 1: roughing with T1, 6 mm flat end mill [flat:6])",  // 2
      "T1",                                                         // 3
      "M3 S12000",                                                  // 4
      "G0 Z5",                                                      // 5
      "G0 X0 Y0",                                                   // 6
      "G1 Z-1 F300",                                                // 7
      "G1 X10 F800",                                                // 8
      "G0 Z5",                                                      // 9
      "(operation 2: finishing with T2, 3.175 mm ball-nose end mill)",  // 10: wrapped
      "([ball:3.175])",                                             // 11
      "M5",                                                         // 12
      "(TOOL CHANGE for finishing: mount T2 ...)",                  // 13
      "T2",                                                         // 14
      "M0",                                                         // 15
      "G21 G90 G17 G94",                                            // 16
      "M3 S18000",                                                  // 17
      "G0 X0 Y10",                                                  // 18
      "G1 Z-1.5 F300",                                              // 19
      "G1 X10 F800",                                                // 20
      "G0 Z5",                                                      // 21
      "M5",                                                         // 22
      "M2",                                                         // 23
  };
  in.from_line = 8;
  jobs::ResumePlan plan = jobs::plan_resume(in);
  ASSERT_TRUE(plan.operation);
  EXPECT_EQ(plan.operation->number, 1);
  EXPECT_EQ(plan.operation->tool, 1);
  EXPECT_EQ(plan.operation->cutter, "6 mm flat end mill [flat:6]");
  // Past the tool change's pause the ball is in the spindle.
  in.from_line = 19;
  plan = jobs::plan_resume(in);
  ASSERT_TRUE(plan.operation);
  EXPECT_EQ(plan.operation->name, "finishing");
  EXPECT_EQ(plan.operation->tool, 2);
  EXPECT_EQ(plan.operation->cutter, "3.175 mm ball-nose end mill [ball:3.175]");
  // Before it (the pause runs again) the flat still is.
  in.from_line = 13;
  EXPECT_EQ(jobs::plan_resume(in).operation->tool, 1);
  // A program of no operations names none.
  EXPECT_FALSE(jobs::plan_resume(input()).operation);
}
