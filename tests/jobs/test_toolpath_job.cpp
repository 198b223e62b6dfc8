// The tool path job called directly, as a daemon's worker would: progress,
// cancellation from another thread (the operations beside the finishing
// too), a mesh instead of a file, and a result that does not depend on the
// thread limit.
#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <exception>
#include <iostream>
#include <memory>
#include <mutex>
#include <stop_token>
#include <thread>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/geometry/stl.hpp"
#include "cncstream/jobs/toolpath_job.hpp"
#include "jobs_test_util.hpp"
#include "support/v_groove_job.hpp"

using namespace cncstream;
using namespace jobstest;

namespace {

jobs::ToolpathParams plaque_params() {
  jobs::ToolpathParams p;
  p.part.stl = plaque();
  p.cutter = cam::parse_cutter_spec("ball:3.175");
  p.stepover = 0.4;
  p.step = 0.05;
  return p;
}

}  // namespace

TEST(ToolpathJob, ReportsIncreasingProgressEndingAtOne) {
  const fs::path dir = temp_dir("progress");
  jobs::ToolpathParams p = plaque_params();
  p.output = dir / "plaque.nc";
  ProgressLog log;
  jobs::JobControl control;
  control.progress = log.callback();
  const jobs::ToolpathProgram r = jobs::generate_toolpath(p, control);

  ASSERT_GE(log.reports.size(), 10u) << "progress inside the long stages too";
  EXPECT_EQ(log.reports.front().first, "load");
  EXPECT_EQ(log.reports.front().second, 0.0);
  for (std::size_t k = 1; k < log.reports.size(); ++k)
    EXPECT_GE(log.reports[k].second, log.reports[k - 1].second) << "report " << k << " (" << log.reports[k].first << ")";
  EXPECT_EQ(log.reports.back().first, "done");
  EXPECT_EQ(log.reports.back().second, 1.0);
  std::size_t inside_path = 0;
  for (const auto& [stage, f] : log.reports) inside_path += stage == "tool path";
  EXPECT_GT(inside_path, 5u);

  // The program is complete and written.
  EXPECT_GT(r.stats.lines, 20000u);
  EXPECT_NE(r.gcode.find("M2"), std::string::npos);
  EXPECT_EQ(fs::file_size(p.output), r.gcode.size());
  EXPECT_EQ(names_in(dir), std::vector<std::string>{"plaque.nc"});  // no temporary left beside it
}

TEST(ToolpathJob, SameProgramFromAMeshAndWithOneThread) {
  jobs::ToolpathParams p = plaque_params();
  p.stepover = 1.0;
  p.step = 0.1;
  const jobs::ToolpathProgram from_file = jobs::generate_toolpath(p);
  jobs::ToolpathParams q = p;
  q.part.mesh = std::make_shared<const geometry::Mesh>(geometry::load_stl(plaque()).mesh);
  q.part.stl = plaque();  // names it in the header only
  jobs::JobControl one;
  one.threads = 1;
  const jobs::ToolpathProgram from_mesh = jobs::generate_toolpath(q, one);
  EXPECT_EQ(from_file.gcode, from_mesh.gcode);
  EXPECT_EQ(from_file.facets, from_mesh.facets);
}

TEST(ToolpathJob, StopFromAnotherThreadCancelsAndWritesNothing) {
  const fs::path dir = temp_dir("cancel");
  jobs::ToolpathParams p = plaque_params();
  p.output = dir / "plaque.nc";
  // From the block with a roughing cutter: the roughing's path runs beside
  // the finishing, and the stop must end it too.
  p.stock = jobs::StockSpec{};
  p.rough = cam::parse_cutter_spec("flat:6");

  std::stop_source stop;
  std::mutex mutex;
  std::condition_variable cv;
  bool in_path = false;
  std::size_t reports_at_stop = 0, reports_total = 0;
  double last_fraction = 0;
  jobs::JobControl control;
  control.stop = stop.get_token();
  control.progress = [&](std::string_view stage, double fraction) {
    std::lock_guard lock(mutex);
    ++reports_total;
    last_fraction = fraction;
    if (stage == "tool path" && fraction > 0.2 && !in_path) {
      in_path = true;
      cv.notify_all();
    }
  };
  std::exception_ptr error;
  bool returned = false;
  std::chrono::steady_clock::time_point stopped_at, ended_at;
  std::thread worker([&] {
    try {
      jobs::generate_toolpath(p, control);
      returned = true;
    } catch (...) {
      error = std::current_exception();
    }
    ended_at = std::chrono::steady_clock::now();
  });
  {
    // Request the stop from this thread once the job is inside the tool path
    // (the CL grid or the rows, the longest stage).
    std::unique_lock lock(mutex);
    cv.wait(lock, [&] { return in_path; });
    reports_at_stop = reports_total;
    stopped_at = std::chrono::steady_clock::now();
    stop.request_stop();
  }
  worker.join();
  // For the record only: a loaded machine may take longer, so no bound.
  std::cout << "cancelled " << std::chrono::duration<double, std::milli>(ended_at - stopped_at).count()
            << " ms after the stop request\n";

  EXPECT_FALSE(returned) << "the job ran to the end despite the stop";
  ASSERT_TRUE(error);
  EXPECT_THROW(std::rethrow_exception(error), jobs::Cancelled);
  // Progress stopped: at most a report already under way when the stop came,
  // never the G-code stage or the end.
  EXPECT_LE(reports_total, reports_at_stop + 1);
  EXPECT_LT(last_fraction, 0.85);
  // No output, complete-looking or partial.
  EXPECT_FALSE(fs::exists(p.output));
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST(ToolpathJob, OperationsBesideTheFinishingGiveTheSameProgramAsOneThread) {
  // The roughing's path and the rest machining run beside the finishing;
  // with one thread they run after it. The program is the same either way.
  jobs::ToolpathParams p = test::v_groove_job("ball:6", "ball:2");
  p.rough = cam::parse_cutter_spec("flat:6");
  p.stock = jobs::StockSpec{};
  p.stepover = 1.0;
  p.step = 0.1;
  // A rest roughing too: limited to 2 mm a cut, the finishing ball finds
  // more than that left in the groove by the flat's terraces.
  p.max_depth = 2.0;
  const jobs::ToolpathProgram beside = jobs::generate_toolpath(p);
  jobs::JobControl one;
  one.threads = 1;
  const jobs::ToolpathProgram after = jobs::generate_toolpath(p, one);
  EXPECT_TRUE(beside.stages_overlap);
  std::vector<std::string> names;
  for (const auto& o : beside.operations) names.push_back(o.name);
  EXPECT_EQ(names, (std::vector<std::string>{"roughing", "rest roughing", "finishing", "rest machining"}));
  EXPECT_EQ(beside.gcode, after.gcode);
  EXPECT_EQ(beside.notes, after.notes);
}

TEST(ToolpathJob, StopRequestedBeforeTheStartCancelsAtOnce) {
  const fs::path dir = temp_dir("cancel-early");
  jobs::ToolpathParams p = plaque_params();
  p.output = dir / "plaque.nc";
  std::stop_source stop;
  stop.request_stop();
  ProgressLog log;
  jobs::JobControl control;
  control.stop = stop.get_token();
  control.progress = log.callback();
  EXPECT_THROW(jobs::generate_toolpath(p, control), jobs::Cancelled);
  EXPECT_TRUE(log.reports.empty());
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST(ToolpathJob, TwoJobsAtOnceGiveTheProgramsOfOneAtATime) {
  // Two workers computing at once share oneTBB's pool; neither result
  // depends on how the other's tasks were interleaved with its own.
  jobs::ToolpathParams a = plaque_params(), b = plaque_params();
  a.stepover = b.stepover = 1.0;
  a.step = b.step = 0.1;
  b.cutter = cam::parse_cutter_spec("bull:3.175:0.79");
  const std::string alone_a = jobs::generate_toolpath(a).gcode;
  const std::string alone_b = jobs::generate_toolpath(b).gcode;
  std::string together_a, together_b;
  std::thread ta([&] { together_a = jobs::generate_toolpath(a).gcode; });
  std::thread tb([&] { together_b = jobs::generate_toolpath(b).gcode; });
  ta.join();
  tb.join();
  EXPECT_EQ(together_a, alone_a);
  EXPECT_EQ(together_b, alone_b);
}
