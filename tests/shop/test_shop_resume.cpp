// Resume or restart (issue 29, docs/shop.md): a job whose PC died mid-cut is
// interrupted at its last reported line; requeued on the same machine, only
// that machine claims it and its daemon queues it as a resume from that line
// (the preamble, then the rest of the file), waiting for the operator;
// requeued anywhere, it is a restart from the top.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cncstream/shop/hub.hpp"
#include "cncstream/shop/schema.hpp"
#include "cncstream/transport/journal.hpp"
#include "shop_daemon_util.hpp"
#include "shop_test_util.hpp"

using namespace cncstream;
namespace fs = std::filesystem;
using shop::PgConnection;

namespace detail_shop_resume {

// 400 moves of 2.5 mm at 1500 mm/min: a tenth of a second each at real-time
// speed, so the first run is mid-way for many seconds.
std::string long_program() {
  std::string p = "G21\nG90\nG1 F1500\n";
  for (int i = 0; i < 400; ++i) p += i % 2 ? "G1 X0\n" : "G1 X2.5\n";
  return p;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start < text.size()) {
    const auto end = text.find('\n', start);
    out.push_back(text.substr(start, end - start));
    start = end == std::string::npos ? text.size() : end + 1;
  }
  return out;
}


// What a machine's session was given to stream when its job started.
struct StartedJob {
  std::mutex mu;
  std::vector<std::string> lines;
  std::int64_t from_line = -1;
  bool started = false;
};

}  // namespace detail_shop_resume

TEST(ShopResume, RequeuedOnItsMachineTheJobIsAResumeFromItsLastLineThereAndAnywhereARestart) {
  SHOP_REQUIRE_POSTGRES();
  using detail_shop_resume::lines_of;
  shoptest::TempPostgres pg;
  const std::string url = pg.create_database("resume");
  PgConnection admin(url);
  shop::migrate(admin);
  shop::Hub hub(admin);
  shop::Submission s;
  s.file_name = "long.nc";
  s.kind = "gcode";
  s.content = detail_shop_resume::long_program();
  const auto program = lines_of(s.content);
  const std::int64_t job = hub.submit_job(s);
  const fs::path dir = dtest::temp_dir("shop-resume");
  const auto config = [&](const std::string& pc, const std::string& machine, const std::string& speed) {
    auto c = shoptest::shop_daemon_config(dir / pc, url, {dtest::sim_machine(machine, speed)});
    c.shop.lease_s = 2;
    c.shop.heartbeat_s = 0.3;
    return c;
  };
  const auto job_row = [&](std::int64_t id) {
    return admin.exec("SELECT j.status, j.last_line, j.resume_after_line, m.name, j.message FROM shop.jobs j"
                      " LEFT JOIN shop.machines m ON m.id = j.machine_id WHERE j.id = $1",
                      {std::to_string(id)});
  };

  // PC A's daemon in a child process: routerA claims the job, its operator
  // starts it, and the PC dies mid-cut (kill -9).
  {
    shoptest::DaemonChild a;
    a.pid = ::fork();
    ASSERT_GE(a.pid, 0);
    if (a.pid == 0) {
      ::prctl(PR_SET_PDEATHSIG, SIGKILL);
      try {
        dtest::RunningDaemon d(config("pc-a", "routerA", "1"));
        while (shoptest::start_ready_jobs(d.daemon()) == 0) ::usleep(50'000);
        ::pause();
      } catch (...) {
        ::_exit(1);
      }
      ::_exit(0);
    }
    ASSERT_TRUE(dtest::wait_for([&] { return job_row(job).text(0, 0) == "running" && job_row(job).i64(0, 1) >= 30; }, 30))
        << "routerA should claim, run and report the job past line 30; it is " << job_row(job).text(0, 0);
    a.kill9();
  }

  // PC B joins with an idle machine that could do the job.
  dtest::RunningDaemon b(config("pc-b", "routerB", "max"));
  // PC A comes back (its journal, its machine): its recovery interrupts the
  // local job and ships that with its last answered line.
  auto a2 = std::make_unique<dtest::RunningDaemon>(config("pc-a", "routerA", "max"));
  ASSERT_TRUE(dtest::wait_for([&] { return job_row(job).text(0, 0) == "interrupted"; }, 15))
      << "the job should be interrupted; it is " << job_row(job).text(0, 0);
  const std::int64_t last_line = job_row(job).i64(0, 1);
  ASSERT_GE(last_line, 30);
  const auto first_run = shoptest::on_loop(a2->daemon(), [&] { return a2->daemon().jobs().list(std::nullopt, std::nullopt); });
  ASSERT_EQ(first_run["jobs"].size(), 1u) << first_run.dump();
  const std::int64_t first_local = first_run["jobs"][0]["id"].get<std::int64_t>();
  EXPECT_EQ(first_run["jobs"][0]["state"], "interrupted");

  // The operator requeues it on the same machine: it carries the line, and only routerA claims it.
  hub.requeue_job(job, true);
  EXPECT_EQ(job_row(job).i64(0, 2), last_line);
  ASSERT_TRUE(dtest::wait_for([&] {
    const auto r = job_row(job);
    return r.text(0, 0) == "awaiting_operator" && r.text(0, 3) == "routerA";
  }, 15)) << "routerA should claim the resume; the job is " << job_row(job).text(0, 0) << " on " << job_row(job).text(0, 3);
  EXPECT_NE(job_row(job).text(0, 4).find("resumes after line"), std::string::npos) << job_row(job).text(0, 4);
  const auto b_jobs = shoptest::on_loop(b.daemon(), [&] { return b.daemon().jobs().list(std::nullopt, std::nullopt); });
  EXPECT_EQ(b_jobs["jobs"].size(), 0u) << "routerB took a resume meant for routerA: " << b_jobs.dump();

  // The local job is a resume of the first run, chosen as `cncstream resume`
  // chooses from that line (never past it), and waits for the operator.
  nlohmann::json resume;
  ASSERT_TRUE(dtest::wait_for([&] {
    const auto l = shoptest::on_loop(a2->daemon(), [&] { return a2->daemon().jobs().list(std::nullopt, std::string("ready")); });
    if (l["jobs"].empty()) return false;
    resume = l["jobs"][0];
    return true;
  }, 15)) << "routerA's resume never became ready";
  const std::int64_t resume_local = resume["id"].get<std::int64_t>();
  const auto full = shoptest::on_loop(a2->daemon(), [&] { return a2->daemon().jobs().to_json(a2->daemon().jobs().get(resume_local)); });
  EXPECT_EQ(full["resumed_from"], first_local) << full.dump();
  const std::int64_t from_line = full["from_line"].get<std::int64_t>();
  EXPECT_GT(from_line, 3) << full.dump();
  EXPECT_LE(from_line, last_line) << "a resume must never skip a line the machine may not have cut";
  EXPECT_GE(from_line, last_line - 40) << full.dump();
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  auto* machine_a = shoptest::on_loop(a2->daemon(), [&] { return a2->daemon().machines().find("routerA"); });
  ASSERT_NE(machine_a, nullptr);
  EXPECT_FALSE(machine_a->session->job_active()) << "a claimed resume started by itself";

  // The operator starts it: the machine gets the resume preamble (safe Z,
  // spindle, XY, then Z) and then the file after the chosen line.
  auto started = std::make_shared<detail_shop_resume::StartedJob>();
  auto sub = shoptest::on_loop(a2->daemon(), [&] {
    return machine_a->session->subscribe([started](const session::SessionEvent& e) {
      if (e.kind != session::SessionEventKind::JobStarted || !e.job) return;
      std::lock_guard lk(started->mu);
      started->lines = e.job->lines;
      started->from_line = e.job->from_line;
      started->started = true;
    });
  });
  ASSERT_EQ(shoptest::start_ready_jobs(a2->daemon()), 1);
  ASSERT_TRUE(dtest::wait_for([&] { return job_row(job).text(0, 0) == "completed"; }, 20))
      << "the resume should run to its end; the job is " << job_row(job).text(0, 0);
  {
    std::lock_guard lk(started->mu);
    ASSERT_TRUE(started->started);
    EXPECT_EQ(started->from_line, from_line);
    const std::size_t rest = program.size() - static_cast<std::size_t>(from_line);
    ASSERT_GT(started->lines.size(), rest);
    const std::size_t preamble = started->lines.size() - rest;
    for (std::size_t i = 0; i < rest; ++i)
      ASSERT_EQ(started->lines[preamble + i], program[static_cast<std::size_t>(from_line) + i]) << "line " << i;
    // Safe Z first, then XY, then down to the cut.
    std::string pre;
    for (std::size_t i = 0; i < preamble; ++i) pre += started->lines[i] + "\n";
    const auto z_up = pre.find("Z");
    const auto xy = pre.find("X");
    ASSERT_NE(z_up, std::string::npos) << pre;
    ASSERT_NE(xy, std::string::npos) << pre;
    EXPECT_LT(z_up, xy) << "the preamble must retract before it travels:\n" << pre;
  }
  // The journal records the run as a resume after that line.
  const auto done = shoptest::on_loop(a2->daemon(), [&] { return a2->daemon().jobs().to_json(a2->daemon().jobs().get(resume_local)); });
  EXPECT_EQ(done["state"], "done") << done.dump();
  ASSERT_TRUE(done["journal_id"].is_number()) << done.dump();
  {
    transport::Journal journal(dir / "pc-a" / "journal.sqlite");
    const auto rec = journal.job(done["journal_id"].get<std::int64_t>());
    ASSERT_TRUE(rec);
    EXPECT_EQ(rec->from_line, from_line);
    EXPECT_EQ(rec->outcome.value_or(""), "completed");
  }
  EXPECT_EQ(admin.exec("SELECT count(*) FROM shop.job_events e JOIN shop.machines m ON m.id = e.machine_id"
                       " WHERE m.name = 'routerB' AND e.job_id = $1", {std::to_string(job)}).i64(0, 0), 0);

  // Requeued anywhere (after the hub interrupted it once more at line 50): a
  // restart from the top on whichever machine claims it.
  admin.exec("UPDATE shop.jobs SET status = 'interrupted', last_line = 50, ended_at = now() WHERE id = $1",
             {std::to_string(job)});
  hub.requeue_job(job, false);
  EXPECT_TRUE(job_row(job).is_null(0, 2));
  ASSERT_TRUE(dtest::wait_for([&] { return job_row(job).text(0, 0) == "awaiting_operator"; }, 15))
      << "the restart was not claimed; it is " << job_row(job).text(0, 0);
  const std::string restarted_on = job_row(job).text(0, 3);
  auto& d = restarted_on == "routerA" ? a2->daemon() : b.daemon();
  nlohmann::json restart;
  ASSERT_TRUE(dtest::wait_for([&] {
    const auto l = shoptest::on_loop(d, [&] { return d.jobs().list(std::nullopt, std::string("ready")); });
    if (l["jobs"].empty()) return false;
    restart = shoptest::on_loop(d, [&] { return d.jobs().to_json(d.jobs().get(l["jobs"][0]["id"].get<std::int64_t>())); });
    return true;
  }, 15));
  EXPECT_EQ(restart["resumed_from"], 0) << restart.dump();
  EXPECT_EQ(restart["from_line"], 0) << restart.dump();
  shoptest::on_loop(a2->daemon(), [&] {
    sub = {};
    return 0;
  });
  a2.reset();
  b.shutdown();
  std::error_code ec;
  fs::remove_all(dir, ec);
}
