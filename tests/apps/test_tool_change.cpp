// Tool changes end to end: the main command on a small part (the V-groove
// of tests/support) roughed with a 6 mm flat and finished with a 3 mm ball
// whose stick-out is 7.3 mm longer, on the built-in simulator whose
// operator mounts each tool when asked. Measured (plate, sensor) the cut
// matches the design; passed through as a pause (the old way) the same job
// gouges by the difference. And a routine that cannot finish (no plate, a
// lost link) ends the job with the tool's length unknown in the journal.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>

#include "app_run.hpp"
#include "cncstream/cam/deviation.hpp"
#include "cncstream/cam/height_field_io.hpp"
#include "cncstream/geometry/stl.hpp"
#include "cncstream/transport/journal.hpp"
#include "support/v_groove.hpp"

using namespace apptest;

namespace {

std::string v_groove_stl() {
  const auto path = temp_dir() / "v_groove.stl";
  if (!fs::exists(path)) cncstream::geometry::write_stl_binary(path, cncstream::test::v_groove());
  return path.string();
}

const char* kTools = "1=flat:6@30,2=ball:3@37.3";

AppRun run_job(const std::string& method, const std::string& tools = kTools, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> args{v_groove_stl(), "sim", "--tool", "ball:3", "--rough", "flat:6", "--stepover", "1",
                                "--tolerance", "0.02", "--sim-resolution", "0.2", "--sim-tool-table", tools,
                                "--tool-change-method", method, "--yes"};
  args.insert(args.end(), extra.begin(), extra.end());
  return run_cncstream(args, 300);
}

std::optional<double> largest_gouge(const std::string& out) {
  const std::regex re("largest gouge (-?[0-9.]+) mm");
  std::smatch m;
  if (!std::regex_search(out, m, re)) return std::nullopt;
  return std::stod(m[1]);
}

// A small program with a tool change (T2 + M0), for the failure cases.
std::string changing_program() {
  const auto path = temp_dir() / "change.nc";
  std::ofstream(path) << "G21 G90 G17 G94\nT1\nM3 S10000\nG0 Z15\nG0 X5 Y5\nG1 Z12 F300\nG1 X30 F600\nG0 Z15\nM5\n"
                         "(TOOL CHANGE: mount T2)\nT2\nM0\nG21 G90 G17 G94\nM3 S10000\nG0 Z15\nG0 X5 Y10\n"
                         "G1 Z12 F300\nG1 X30 F600\nG0 Z15\nM5\nM2\n";
  return path.string();
}

AppRun run_program(std::vector<std::string> extra) {
  std::vector<std::string> args{changing_program(), "sim", "--sim-design", v_groove_stl(), "--sim-tool", "ball:3",
                                "--sim-tool-table", kTools, "--yes"};
  args.insert(args.end(), extra.begin(), extra.end());
  return run_cncstream(args, 120);
}

std::vector<cncstream::transport::ToolChangeRow> last_job_tool_changes() {
  cncstream::transport::Journal j(journal());
  const auto jobs = j.jobs(1);
  if (jobs.empty()) return {};
  return j.tool_changes(jobs.front().id);
}

}  // namespace

// The cut a measured change leaves must be the one equal lengths leave:
// no gouge beyond the path's own (the V-groove's finishing at 0.02 mm
// tolerance reaches 0.0001 mm below the design on the 0.2 mm grid), the
// same material removed.
// `operator_says`, `done_says`: what the simulated operator and the change's
// end print (by default the measuring methods' texts).
void expect_same_cut_as_equal_lengths(const std::string& method, const std::vector<std::string>& extra = {},
                                      std::string operator_says = "(simulator: the operator mounts T2 and confirms)",
                                      std::string done_says = {}) {
  if (done_says.empty()) done_says = "tool change: T2 measured +7.300 mm from T1 (" + method + ")";
  const auto equal = run_job(method, "1=flat:6@30,2=ball:3@30", extra);
  ASSERT_EQ(equal.code, 0) << equal.out;
  const auto r = run_job(method, kTools, extra);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has(operator_says)) << r.out;
  EXPECT_TRUE(r.has(done_says)) << r.out;
  EXPECT_TRUE(r.has("outcome: completed")) << r.out;
  EXPECT_TRUE(r.has(": 0 gouged,")) << r.out;
  EXPECT_FALSE(r.has("PAUSED at line")) << "the M0 never reached the controller: " << r.out;
  const double g = largest_gouge(r.out).value_or(0), g_equal = largest_gouge(equal.out).value_or(0);
  EXPECT_LT(g, 0.002) << r.out;
  EXPECT_NEAR(g, g_equal, 0.0005) << r.out;
  const std::regex re("sim: ([0-9.]+) mm\\^3 removed");
  std::smatch a, b;
  ASSERT_TRUE(std::regex_search(r.out, a, re)) << r.out;
  ASSERT_TRUE(std::regex_search(equal.out, b, re)) << equal.out;
  EXPECT_NEAR(std::stod(a[1]), std::stod(b[1]), 1e-4 * std::stod(b[1])) << "the same material removed";
}

TEST(ToolChange, PlateMeasuresTheLongerFinishingToolAndCutsAsWithEqualLengths) {
  expect_same_cut_as_equal_lengths("plate");
  const auto changes = last_job_tool_changes();
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].tool, 2);
  EXPECT_TRUE(changes[0].length_known);
  ASSERT_TRUE(changes[0].offset_z);
  EXPECT_NEAR(*changes[0].offset_z, 7.3, 0.0015);
}

// The cut the job's simulator writes is in work coordinates whichever tool
// ends the job: after the change to the longer tool it still sits on the
// design (it came out 7.3 mm below it: `view --cut` showed every node
// gouged). Placed as the viewer places it, by the model's offset it records.
TEST(ToolChange, TheCutWrittenAfterTheChangeSitsOnTheDesign) {
  const auto cut = temp_dir() / "changed-cut.f32";
  const auto r = run_job("plate", kTools, {"--sim-result", cut.string(), "--no-journal"});
  ASSERT_EQ(r.code, 0) << r.out;
  ASSERT_TRUE(r.has("tool change: T2 measured +7.300 mm from T1 (plate)")) << r.out;
  cncstream::cam::HeightFieldData field = cncstream::cam::read_height_field(cut);
  ASSERT_TRUE(field.work_offset);
  const cncstream::geometry::Vec3 w = *field.work_offset;
  field.grid.x0 -= w.x;
  field.grid.y0 -= w.y;
  const auto design = cncstream::cam::design_heights(cncstream::geometry::load_stl(v_groove_stl()).mesh, field.grid);
  std::size_t on_part = 0, gouged = 0;
  for (std::size_t k = 0; k < field.z.size(); ++k) {
    if (design.off_part[k] || std::isnan(field.z[k])) continue;
    ++on_part;
    if (static_cast<double>(field.z[k]) - w.z < design.z[k] - 0.05) ++gouged;
  }
  EXPECT_GT(on_part, 1000u);
  EXPECT_EQ(gouged, 0u) << "of " << on_part;
}

TEST(ToolChange, SensorMeasuresTheLongerFinishingToolAndCutsAsWithEqualLengths) {
  expect_same_cut_as_equal_lengths("sensor");
}

TEST(ToolChange, GrblHalsOwnChangeWithTheOperatorsZeroCutsAsWithEqualLengths) {
  // The controller method on the simulated grblHAL ($341=0): the M6 goes to
  // the controller, the simulated operator mounts T2 in its Tool state,
  // touches the tip off on the work (Z zeroed there) and confirms.
  expect_same_cut_as_equal_lengths("controller", {"--sim-firmware", "grblhal"},
                                   "(simulator: the operator mounts T2, zeroes Z on the work and confirms)",
                                   "tool change: the operator zeroed Z with T2 in the controller's Tool state; work Z "
                                   "offset now 7.300");
  const auto changes = last_job_tool_changes();
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].tool, 2);
  EXPECT_EQ(changes[0].method, "controller");
  EXPECT_TRUE(changes[0].length_known);
  ASSERT_TRUE(changes[0].offset_z);
  EXPECT_NEAR(*changes[0].offset_z, 7.3, 0.0015);
}

TEST(ToolChange, GrblHalsOwnChangeIsRefusedOnGrbl11) {
  const auto r = run_job("controller", kTools, {"--sim-firmware", "grbl"});
  EXPECT_NE(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("GRBL 1.1 answers M6 with error:20")) << r.out;
}

TEST(ToolChange, TheOldPauseWithoutMeasuringGougesByTheLengthDifference) {
  // The negative control: the M0 goes to the controller, the simulated
  // operator mounts T2 and resumes, nothing is measured.
  const auto r = run_job("pause");
  EXPECT_EQ(r.code, 3) << r.out;  // gouged
  EXPECT_TRUE(r.has("PAUSED at line")) << r.out;
  const auto g = largest_gouge(r.out);
  ASSERT_TRUE(g) << r.out;
  EXPECT_NEAR(*g, 7.3, 0.15) << r.out;
}

TEST(ToolChange, NoPlateWhereTheRoutineProbesEndsTheJobInAlarmWithTheLengthUnknown) {
  // The plate lies elsewhere: the probe runs its travel and GRBL raises ALARM:5.
  const auto r = run_program({"--tool-change-method", "plate", "--sim-touch-plate", "20,20,5", "--touch-plate-at",
                              "60,60", "--probe-travel", "20"});
  EXPECT_NE(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("ALARM:5")) << r.out;
  EXPECT_TRUE(r.has("outcome: alarm")) << r.out;
  EXPECT_TRUE(r.has("the length of the tool in the spindle is unknown")) << r.out;
  const auto changes = last_job_tool_changes();
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_FALSE(changes[0].length_known);
}

TEST(ToolChange, ALostLinkMidRoutineEndsTheJobDisconnectedWithTheLengthUnknown) {
  // How many answers the whole job takes; after the operator mounted T2
  // come 22: the new tool's measuring (6 lines), $#, G10, $#, the return
  // (4) and the program's last 9 lines. The link goes 19 before the end:
  // in the middle of measuring T2.
  // (Its verify finds the hole the tool makes rising from the machine's
  // origin, inside this design's box: not this test's concern.)
  const auto full = run_program({"--tool-change-method", "sensor"});
  ASSERT_TRUE(full.has("outcome: completed")) << full.out;
  std::smatch m;
  const std::regex re("sim: [0-9]+ lines received, ([0-9]+) answered");
  ASSERT_TRUE(std::regex_search(full.out, m, re)) << full.out;
  const int answered = std::stoi(m[1]);
  const auto r = run_program({"--tool-change-method", "sensor", "--sim-vanish-after", std::to_string(answered - 19)});
  EXPECT_NE(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("outcome: disconnected")) << r.out;
  EXPECT_TRUE(r.has("the length of the tool in the spindle is unknown")) << r.out;
  const auto changes = last_job_tool_changes();
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].tool, 2) << "the operator had been asked to mount T2";
  EXPECT_FALSE(changes[0].length_known);
}

// `cncstream toolchange` on the simulator's bench (T1 30 mm, T2 7.3 mm
// longer, a sensor): measure, change to T2 with the offset written, check
// against the printed trigger; a bit shorter than its trigger fails the
// check (exit 1); a sensor that is not there stops at the end of the travel.
TEST(ToolChange, TheToolchangeCommandMeasuresChangesAndChecksOutsideAJob) {
  auto r = run_cncstream({"toolchange", "measure", "sim", "--yes"});
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("T1 is the reference: it triggered the sensor at machine Z0.000")) << r.out;
  r = run_cncstream({"toolchange", "change", "T2", "sim", "--yes"});
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("T2 measured +7.300 mm from T1 (sensor); work Z offset now 7.300")) << r.out;
  EXPECT_TRUE(r.has("check it later with --trigger 7.300")) << r.out;
  r = run_cncstream({"toolchange", "check", "sim", "--trigger", "0"});
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("T1 is within 0.100 mm")) << r.out;
  // Recorded 1.2 mm higher than it triggers now: a broken bit.
  r = run_cncstream({"toolchange", "check", "sim", "--trigger", "1.2"});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("T1 is 1.200 mm shorter than when it was measured")) << r.out;
  r = run_cncstream({"toolchange", "check", "sim"});
  EXPECT_NE(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("--trigger")) << r.out;
  r = run_cncstream({"toolchange", "measure", "sim", "--sim-tool-sensor", "200,200,0", "--probe-travel", "20"});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("the probe never triggered within 20.000 mm")) << r.out;
}
