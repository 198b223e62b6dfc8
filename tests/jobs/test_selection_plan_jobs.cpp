// The selection and plan jobs called directly: the same numbers and programs
// as `cncstream select` / `plan` printed and wrote before the jobs layer
// existed (plaque, stepover 1 mm, step 0.2 mm, scallop tolerance 0.05 mm),
// whatever the thread limit; the report and plan files; and the G-code
// lattice shared with the tool path job.
#include <gtest/gtest.h>

#include <algorithm>

#include <fstream>
#include <initializer_list>
#include <sstream>
#include <stop_token>
#include <string>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/geometry/stl.hpp"
#include "cncstream/gcode/job_program.hpp"
#include "cncstream/jobs/plan_job.hpp"
#include "cncstream/jobs/selection_job.hpp"
#include "cncstream/jobs/selection_report.hpp"
#include "cncstream/jobs/toolpath_job.hpp"
#include "cncstream/transport/sha256.hpp"
#include "jobs_test_util.hpp"

using namespace cncstream;
using namespace jobstest;

namespace {

jobs::SelectionParams coarse_plaque() {
  jobs::SelectionParams p;
  p.part.stl = plaque();
  p.cutters = cam::CutterPair(cam::parse_cutter_spec("ball:3.175"), cam::parse_cutter_spec("bull:3.175:0.79"));
  p.stepover = 1;
  p.step = 0.2;
  p.scallop_tol = 0.05;
  return p;
}

// The table without its last line (the timings).
std::string without_time(const std::string& table) {
  const auto p = table.rfind("time: ");
  return p == std::string::npos ? table : table.substr(0, p);
}

// As printed by `cncstream select` (rows fitted in the band since issue 26).
const char* const kSelectTable =
    "cutters: 3.175 mm ball-nose end mill [ball:3.175] vs 3.175 mm bull-nose end mill, 0.79 mm corner radius [bull:3.175:0.79]\n"
    "d_base: volume 0.4183 mm, area 0.5412 mm (corrected forms)\n"
    "radiused removes more on 82.1 % of the part by volume, 73.7 % by area (ball: the rest)\n"
    "switch slope: volume 34.6 deg (plane), 37.0 deg measured on the part; area 21.7 deg (plane), 26.9 deg measured\n"
    "scallop heights, stepover 1.000 mm (Table 4.1 form):\n"
    "  cutter                   method            max mm    min mm    mean mm\n"
    "  ball:3.175               cut simulation    2.0134    0.0000    0.1398\n"
    "  ball:3.175               2-D estimate      1.8455    0.0808    0.1228\n"
    "  bull:3.175:0.79          cut simulation    2.4293    0.0000    0.1264\n"
    "  bull:3.175:0.79          2-D estimate      2.4031    0.0000    0.1317\n"
    "material no stepover removes (gaps and inside corners narrower than the cutter; not counted as scallop):\n"
    "  ball:3.175               max 2.5000 mm at (44.00, 23.41) work, mean 0.0783 mm, more than 0.01 mm on 20.1 % of the part\n"
    "  bull:3.175:0.79          max 2.5000 mm at (42.00, 23.04) work, mean 0.0441 mm, more than 0.01 mm on 11.2 % of the part\n";

}  // namespace

TEST(SelectionJob, SameTableAsTheCliAndTheReportFiles) {
  ProgressLog log;
  jobs::JobControl control;
  control.progress = log.callback();
  const jobs::SelectionResult r = jobs::run_selection(coarse_plaque(), control);
  EXPECT_EQ(without_time(r.table()), kSelectTable);
  ASSERT_FALSE(log.reports.empty());
  for (std::size_t k = 1; k < log.reports.size(); ++k) EXPECT_GE(log.reports[k].second, log.reports[k - 1].second);
  EXPECT_EQ(log.reports.back(), std::make_pair(std::string("done"), 1.0));

  const fs::path dir = temp_dir("select");
  const auto files = jobs::write_selection_report(r, dir / "report");
  ASSERT_EQ(files.size(), 8u);
  EXPECT_EQ(files.front().filename(), "selection.json");
  std::vector<std::string> written;
  for (const auto& f : files) written.push_back(f.filename().string());
  std::sort(written.begin(), written.end());
  EXPECT_EQ(names_in(dir / "report"), written);  // every file there, and no temporary beside them
  std::ifstream csv(dir / "report" / "table_4_1.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header, "cutter,method,max_mm,min_mm,mean_mm,samples");
}

// The tapered ball against ball and bull-nose (issue 28): cut on the same
// passes beside the pair, which keeps its table; the taper's 0.5 mm tip
// leaves higher scallops than the 3.175 mm ball at the same stepover, and
// its narrow cone leaves less where neither can reach the bottom.
TEST(SelectionJob, TaperedBallBesideBallAndBullNose) {
  jobs::SelectionParams p = coarse_plaque();
  p.tapered = cam::parse_cutter_spec("taper:1:5:3.175");
  const jobs::SelectionResult r = jobs::run_selection(p);
  ASSERT_TRUE(r.tapered);
  ASSERT_EQ(r.runs().size(), 3u);
  const std::string table = without_time(r.table());
  std::cout << table;
  // The pair's lines as without the third cutter.
  std::string pair_lines = kSelectTable;
  pair_lines = pair_lines.substr(pair_lines.find('\n'));  // after the cutters line
  for (std::size_t a = 0, b; (b = pair_lines.find('\n', a + 1)) != std::string::npos; a = b) {
    const std::string line = pair_lines.substr(a + 1, b - a - 1);
    if (!line.empty()) {
      EXPECT_NE(table.find(line), std::string::npos) << line;
    }
  }
  EXPECT_NE(table.find(", beside them 1 mm tapered ball-nose"), std::string::npos);
  EXPECT_NE(table.find("  taper:1:5:3.175          cut simulation"), std::string::npos);
  EXPECT_NE(table.find("  taper:1:5:3.175          2-D estimate"), std::string::npos);
  EXPECT_NE(table.find("  taper:1:5:3.175          max "), std::string::npos);  // what it cannot reach
  const jobs::CutterRun& t = *r.tapered;
  EXPECT_GT(t.scallops.stats.mean, 2 * r.ball.scallops.stats.mean);
  EXPECT_GT(t.estimate_2d.mean, 2 * r.ball.estimate_2d.mean);
  ASSERT_TRUE(t.scallops.unreachable_stats.computed);
  EXPECT_LT(t.scallops.unreachable_stats.mean, r.ball.scallops.unreachable_stats.mean);

  const fs::path dir = temp_dir("select_taper");
  (void)jobs::write_selection_report(r, dir / "report");
  std::ifstream csv(dir / "report" / "table_4_1.csv");
  std::vector<std::string> rows;
  for (std::string line; std::getline(csv, line);) rows.push_back(line);
  ASSERT_EQ(rows.size(), 7u);  // the header and two methods of three cutters
  EXPECT_EQ(rows[5].rfind("taper:1:5:3.175,cut_simulation,", 0), 0u) << rows[5];
}

TEST(SelectionJob, SelectionPathsLieOnTheToolpathJobsLattice) {
  // Both jobs place the part and the G-code lattice the same way: the
  // selection's ball path is the tool path job's, point for point.
  jobs::SelectionParams s = coarse_plaque();
  s.reach_pitch = 0;
  const jobs::SelectionResult sel = jobs::run_selection(s);
  jobs::ToolpathParams t;
  t.part.stl = plaque();
  t.cutter = s.cutters.ball;
  t.stepover = s.stepover;
  t.step = s.step;
  t.tolerance = cam::RasterOptions{}.tolerance;  // the selection's rows keep the raster's own
  t.arcs = false;                           // (with arcs the rows take half the tolerance)
  const jobs::ToolpathProgram tp = jobs::generate_toolpath(t);
  ASSERT_EQ(sel.ball.path.rows.size(), tp.path.rows.size());
  for (std::size_t r = 0; r < tp.path.rows.size(); ++r) {
    ASSERT_EQ(sel.ball.path.rows[r].size(), tp.path.rows[r].size()) << "row " << r;
    for (std::size_t k = 0; k < tp.path.rows[r].size(); ++k) {
      EXPECT_EQ(sel.ball.path.rows[r][k].x, tp.path.rows[r][k].x);
      EXPECT_EQ(sel.ball.path.rows[r][k].y, tp.path.rows[r][k].y);
      EXPECT_EQ(sel.ball.path.rows[r][k].z, tp.path.rows[r][k].z);
    }
  }
  EXPECT_EQ(sel.work_offset.x, tp.work_offset.x);
  EXPECT_EQ(sel.work_offset.y, tp.work_offset.y);
  EXPECT_EQ(sel.work_offset.z, tp.work_offset.z);
}

TEST(PlanJob, SameOptionsAndProgramsAsTheCliWithAnyThreadLimit) {
  jobs::PlanParams p;
  p.selection = coarse_plaque();
  // The part as the CLI was given it (it names the part in the programs'
  // headers), from a mesh already loaded.
  p.selection.part.stl = "examples/plaque.stl";
  p.selection.part.mesh = std::make_shared<const geometry::Mesh>(geometry::load_stl(plaque()).mesh);
  // Under the sanitizers (the test command) one run, in a task arena of one
  // thread (`--threads 1`): the CLI's plan tests run without a limit, and
  // ClEngine.SameResultForAnyThreadCount checks the engine for any count.
#if defined(__SANITIZE_ADDRESS__)
  const std::initializer_list<unsigned> thread_limits{1u};
#else
  const std::initializer_list<unsigned> thread_limits{0u, 1u};
#endif
  for (unsigned threads : thread_limits) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    jobs::JobControl control;
    control.threads = threads;
    ProgressLog log;
    control.progress = log.callback();
    const jobs::PlanResult plan = jobs::run_plan(p, control);
    ASSERT_FALSE(log.reports.empty());
    for (std::size_t k = 1; k < log.reports.size(); ++k) EXPECT_GE(log.reports[k].second, log.reports[k - 1].second);
    EXPECT_EQ(log.reports.back(), std::make_pair(std::string("done"), 1.0));

    // As `cncstream plan` printed and wrote them (rows fitted in the band since issue 26).
    EXPECT_TRUE(plan.radiused_first);
    EXPECT_EQ(plan.cleanup_pieces.size(), 225u);
    EXPECT_EQ(transport::sha256_hex(plan.program_first),
              "606b25ba5531c666330b15b3403522ad00800c1ed2f611367911ff034ee62b97");
    EXPECT_EQ(transport::sha256_hex(plan.program_second),
              "c5e6bcae128c5a9f2ca884d86911001c3eab2442e800cccded38c4029dba2319");
    ASSERT_EQ(plan.options.size(), 3u);
    const struct {
      const char* name;
      double seconds, max_residual, share, max_scallop, scallop_share;
    } want[] = {
        {"ball only (ball:3.175)", 2578.9571898486565, 2.5809741076330681, 0.31331125966596113, 2.0344650281357897,
         0.23399274921938851},
        {"radiused only (bull:3.175:0.79)", 2660.8416552251197, 2.5018794326845004, 0.19400658018818501,
         2.4450717103459105, 0.14236467654393428},
        {"combined (bull:3.175:0.79 then ball:3.175 clean-up)", 4465.253346243634, 2.5018633137475437,
         0.14868081896100085, 2.3406388728400618, 0.1030847251618852},
    };
    for (std::size_t k = 0; k < 3; ++k) {
      const jobs::PlanOption& o = plan.options[k];
      EXPECT_EQ(o.name, want[k].name);
      EXPECT_NEAR(o.seconds, want[k].seconds, 1e-6);
      EXPECT_NEAR(o.max_residual, want[k].max_residual, 1e-12);
      EXPECT_NEAR(o.share_above_tol, want[k].share, 1e-12);
      EXPECT_NEAR(o.max_scallop, want[k].max_scallop, 1e-12);
      EXPECT_NEAR(o.scallop_share_above_tol, want[k].scallop_share, 1e-12);
    }

    const fs::path dir = temp_dir("plan");
    const jobs::PlanFiles files = jobs::write_plan(plan, dir);
    EXPECT_EQ(files.first, dir / "plaque-1-bull_3.175_0.79.nc");
    EXPECT_EQ(files.second, dir / "plaque-2-ball_3.175.nc");
    EXPECT_EQ(transport::sha256_file(files.first), transport::sha256_hex(plan.program_first));
    EXPECT_TRUE(fs::exists(files.json));
    // Both as one job: the finishing with T1, the tool change, the clean-up with T2.
    EXPECT_EQ(files.job, dir / "plaque-job.nc");
    EXPECT_EQ(transport::sha256_file(files.job), transport::sha256_hex(plan.program_job));
    std::vector<std::string> lines;
    std::istringstream in(plan.program_job);
    for (std::string l; std::getline(in, l);) lines.push_back(l);
    const auto ops = program_operations(lines);
    ASSERT_EQ(ops.size(), 2u);
    EXPECT_EQ(ops[0].name, "finishing");
    EXPECT_EQ(ops[0].tool, 1);
    EXPECT_NE(ops[0].cutter.find("[bull:3.175:0.79]"), std::string::npos);
    EXPECT_EQ(ops[1].name, "clean-up");
    EXPECT_EQ(ops[1].tool, 2);
    EXPECT_EQ(lines[ops[1].mounted_line - 1], "M0");
    EXPECT_EQ(std::count(lines.begin(), lines.end(), "M0"), 1);
  }
}

TEST(SelectionJob, StopInsideATaskArenaCancels) {
  // With a thread limit the job runs in a task arena of its own; the stop,
  // requested from a worker's progress report, still leaves through it.
  std::stop_source stop;
  jobs::JobControl control;
  control.threads = 1;
  control.stop = stop.get_token();
  std::string stage_at_stop;
  control.progress = [&](std::string_view stage, double) {
    if (stage == "cut simulation" && stage_at_stop.empty()) {
      stage_at_stop = stage;
      stop.request_stop();
    }
    EXPECT_NE(stage, "done");
  };
  EXPECT_THROW(jobs::run_selection(coarse_plaque(), control), jobs::Cancelled);
  EXPECT_EQ(stage_at_stop, "cut simulation");
}
