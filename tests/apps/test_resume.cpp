// Resume from line N: the preamble brings a fresh controller to the program's
// state after line N, so "stop at N, reset, resume" machines the same part,
// ends at the same place and in the same modes as running straight through.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>

#include "app_run.hpp"
#include "cncsim/machine.hpp"
#include "cncsim/removal.hpp"
#include "cncstream/gcode/program.hpp"
#include "cncstream/gcode/resume.hpp"
#include "cncstream/transport/journal.hpp"
#include "sim/sim_test_util.hpp"

using namespace apptest;
using cncstream::geometry::Vec3;

namespace {

// Units, distance modes, G92, spindle and coolant all change along the way.
std::vector<std::string> modal_program() {
  std::vector<std::string> p{"G21 G90 G94 G17", "G0 Z5", "M3 S12000", "M8", "G0 X2 Y2", "G92 X0 Y0", "G1 Z-0.5 F400"};
  for (int i = 0; i < 40; ++i) p.push_back("G1 X" + std::to_string(i * 0.5) + " Y" + std::to_string((i % 2) * 0.3) + " F800");
  p.push_back("G20");
  for (int i = 0; i < 30; ++i) p.push_back("G1 X" + std::to_string(0.8 - i * 0.02) + " Y" + std::to_string(0.1 + (i % 3) * 0.05) + " F30");
  p.push_back("G21");
  p.push_back("G91");
  for (int i = 0; i < 20; ++i) p.push_back(i % 2 ? "X0.2 Y0.1" : "G1 X0.2 Y-0.05 Z-0.01");
  p.insert(p.end(), {"G90", "G0 Z5", "M5 M9", "M2"});
  return p;
}

cncsim::Machine fresh_machine() {
  cncsim::MachineOptions o;
  o.instant_waits = true;
  return cncsim::Machine(o);
}

void run_lines(cncsim::Machine& m, const std::vector<std::string>& lines) {
  for (const auto& l : lines) {
    const auto out = simtest::send(m, l);
    ASSERT_NE(out.find("ok"), std::string::npos) << l << " -> " << out;
  }
  m.run_until_idle();
}

struct Machined {
  Vec3 work;
  std::string modes;
  std::vector<double> heights;
};

Machined straight(const std::vector<std::string>& prog) {
  auto m = fresh_machine();
  cncsim::MaterialRemoval cut(cncsim::StockBox{{-5, -5, -3}, {30, 20, 0}, 0.2}, cncstream::cam::parse_cutter_spec("ball:2"));
  cut.attach(m);
  run_lines(m, prog);
  return {m.work_position(), cncstream::gcode::format_modes(m.parser()), cut.stock().heights()};
}

Machined interrupted(const std::vector<std::string>& prog, std::size_t n) {
  cncsim::MaterialRemoval cut(cncsim::StockBox{{-5, -5, -3}, {30, 20, 0}, 0.2}, cncstream::cam::parse_cutter_spec("ball:2"));
  {
    auto first = fresh_machine();
    cut.attach(first);
    run_lines(first, std::vector<std::string>(prog.begin(), prog.begin() + static_cast<long>(n)));
  }
  // A new controller (reset / power cycle): modes, G92 and spindle are gone.
  auto second = fresh_machine();
  cut.attach(second);
  std::string text;
  for (const auto& l : prog) text += l + "\n";
  const auto at = cncstream::gcode::state_before_line(text, n);
  cncstream::gcode::ResumeOptions ro;
  ro.safe_z = 5;
  ro.dwell_s = 0.5;
  auto lines = cncstream::gcode::resume_preamble(at, ro);
  lines.insert(lines.end(), prog.begin() + static_cast<long>(n), prog.end());
  run_lines(second, lines);
  return {second.work_position(), cncstream::gcode::format_modes(second.parser()), cut.stock().heights()};
}

}  // namespace

TEST(Resume, StopAtLineNThenResumeMachinesTheSamePart) {
  const auto prog = modal_program();
  const Machined a = straight(prog);
  double deepest = 0;
  for (double z : a.heights) deepest = std::min(deepest, z);
  ASSERT_LT(deepest, -0.4) << "the program cuts the stock";
  // N inside the G92 + metric part, the inch part, and the incremental part.
  for (std::size_t n : {20u, 60u, 85u}) {
    SCOPED_TRACE("resume after line " + std::to_string(n));
    const Machined b = interrupted(prog, n);
    EXPECT_NEAR(a.work.x, b.work.x, 1e-6);
    EXPECT_NEAR(a.work.y, b.work.y, 1e-6);
    EXPECT_NEAR(a.work.z, b.work.z, 1e-6);
    EXPECT_EQ(a.modes, b.modes);
    ASSERT_EQ(a.heights.size(), b.heights.size());
    double worst = 0;
    for (std::size_t i = 0; i < a.heights.size(); ++i) worst = std::max(worst, std::abs(a.heights[i] - b.heights[i]));
    EXPECT_LT(worst, 1e-6) << "the resumed cut differs from the straight one";
  }
}

TEST(Resume, PreambleRestoresG92InchesIncrementalAndCoolant) {
  std::string text;
  for (const auto& l : modal_program()) text += l + "\n";
  const auto at = cncstream::gcode::state_before_line(text, 85);
  cncstream::gcode::ResumeOptions ro;
  ro.machine_safe_z = -1;
  ro.safe_z = 5;
  const auto pre = cncstream::gcode::resume_preamble(at, ro);
  std::string all;
  for (const auto& l : pre) all += l + "\n";
  EXPECT_NE(all.find("G53 G0 Z-1\n"), std::string::npos) << all;
  EXPECT_NE(all.find("G92 X"), std::string::npos) << all;
  EXPECT_NE(all.find("M3 S12000\nM8\nG4 P2\n"), std::string::npos) << all;
  EXPECT_NE(all.find("G21 G91 G17 G94\n"), std::string::npos) << all;
  EXPECT_NE(all.find("G1 Z-0."), std::string::npos) << all;  // plunge
}

TEST(Resume, CliResumesADisconnectedJobAndLinksIt) {
  const auto prog = temp_dir() / "resume.nc";
  {
    std::ofstream f(prog);
    for (const auto& l : modal_program()) f << l << "\n";
  }
  const auto db = (temp_dir() / "resume.sqlite").string();
  const auto whole = run_cncstream({prog.string(), "sim", "--journal", db, "--no-journal"});
  ASSERT_EQ(whole.code, 0) << whole.out;
  // At 10 x real time the controller reports its position while the lines run.
  const auto cut =
      run_cncstream({prog.string(), "sim", "--journal", db, "--sim-vanish-after", "40", "--sim-speed", "10"});
  ASSERT_EQ(cut.code, 1) << cut.out;
  ASSERT_TRUE(cut.has("outcome: disconnected")) << cut.out;
  const auto resumed = run_cncstream({"resume", "1", "sim", "--journal", db, "--yes", "--dwell", "0.2"});
  ASSERT_EQ(resumed.code, 0) << resumed.out;
  // The controller answered up to line 38, but its planner may not have run
  // the last moves: resume goes back to the line it was last seen cutting.
  EXPECT_TRUE(resumed.has("(last answered: 38)")) << resumed.out;
  auto final_pos = [](const std::string& out) {
    const auto at = out.find("WPos", out.find("final position"));
    return out.substr(at, out.find(',', out.find(',', at) + 1) - at);  // "WPos x,y"
  };
  EXPECT_EQ(final_pos(whole.out), final_pos(resumed.out)) << whole.out << "\n---\n" << resumed.out;
  cncstream::transport::Journal j(db);
  const auto job = j.job(2);
  ASSERT_TRUE(job);
  EXPECT_EQ(job->resumed_from, 1);
  EXPECT_TRUE(resumed.has("continue after line " + std::to_string(job->from_line) + " of 104")) << resumed.out;
  // The journal kept the controller's last reported position and the line
  // answered when it came; the resumed line is one the planner could still
  // hold then, and its path passes through that position.
  const auto seen = j.last_progress(1);
  ASSERT_TRUE(seen);
  if (!seen->status_work_pos) {
    // Under heavy load the 40 lines may all be answered before the first
    // status poll: then resume backs off one planner queue (lines 23..38 move).
    EXPECT_TRUE(resumed.has("no position report was journaled")) << resumed.out;
    EXPECT_EQ(job->from_line, 38 - 16);
  } else {
    EXPECT_TRUE(resumed.has("the controller last reported the tool at")) << resumed.out;
    EXPECT_GT(seen->status_line, 0);
    EXPECT_LE(seen->status_line, 38);
    EXPECT_LT(job->from_line, seen->status_line);
    EXPECT_GE(job->from_line + 17, seen->status_line);
    std::string text;
    for (const auto& l : modal_program()) text += l + "\n";
    const Vec3 p{(*seen->status_work_pos)[0], (*seen->status_work_pos)[1], (*seen->status_work_pos)[2]};
    double nearest = 1e9;
    for (const auto& s : cncstream::gcode::trace_program(text).segments) {
      if (s.source_line != static_cast<std::size_t>(job->from_line)) continue;
      const Vec3 a = s.work_from(), ab = s.work_to() - a;
      const double t = std::clamp(cncstream::geometry::dot(p - a, ab) / std::max(cncstream::geometry::dot(ab, ab), 1e-300), 0.0, 1.0);
      nearest = std::min(nearest, cncstream::geometry::norm(p - (a + ab * t)));
    }
    EXPECT_LT(nearest, 0.01) << "the resumed line does not pass through the last reported position";
  }
  EXPECT_EQ(job->outcome.value_or(""), "completed");
  EXPECT_EQ(j.last_progress(2)->last_line, 104);
  // A changed file is refused.
  { std::ofstream(prog, std::ios::app) << "G0 X0\n"; }
  const auto refused = run_cncstream({"resume", "1", "sim", "--journal", db, "--yes"});
  EXPECT_EQ(refused.code, 1);
  EXPECT_TRUE(refused.has("changed since job 1")) << refused.out;
}
