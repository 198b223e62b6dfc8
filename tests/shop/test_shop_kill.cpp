// A daemon killed with kill -9 mid-job (issue 29): after its lease the hub
// marks the job interrupted with the last line the daemon reported, and no
// other machine starts it, though another daemon's idle machine keeps
// heart-beating and claiming.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cncstream/shop/hub.hpp"
#include "cncstream/shop/schema.hpp"
#include "shop_daemon_util.hpp"
#include "shop_test_util.hpp"

using namespace cncstream;
namespace fs = std::filesystem;
using shop::PgConnection;

namespace detail_shop_kill {

// 200 moves of 2.5 mm at 600 mm/min: a quarter of a second each on a
// simulator at real-time speed, so the job is mid-way for many seconds.
std::string long_program() {
  std::string p = "G21\nG90\nG1 F600\n";
  for (int i = 0; i < 200; ++i) p += i % 2 ? "G1 X0\n" : "G1 X2.5\n";
  return p;
}


}  // namespace detail_shop_kill

TEST(ShopLease, ADaemonKilledMidJobLeavesItInterruptedAtItsLastLineAndNobodyElseStartsIt) {
  SHOP_REQUIRE_POSTGRES();
  shoptest::TempPostgres pg;
  const std::string url = pg.create_database("kill");
  PgConnection admin(url);
  shop::migrate(admin);
  shop::Hub hub(admin);
  shop::Submission s;
  s.file_name = "long.nc";
  s.kind = "gcode";
  s.content = detail_shop_kill::long_program();
  const std::int64_t job = hub.submit_job(s);
  const fs::path dir = dtest::temp_dir("shop-kill");
  const auto config = [&](const std::string& pc, const std::string& machine) {
    auto c = shoptest::shop_daemon_config(dir / pc, url, {dtest::sim_machine(machine, "1")});
    c.shop.lease_s = 2;
    c.shop.heartbeat_s = 0.3;
    return c;
  };

  // Daemon A in a child process (forked while this one has no thread): its
  // machine claims the only job, and its operator starts it.
  shoptest::DaemonChild a;
  a.pid = ::fork();
  ASSERT_GE(a.pid, 0);
  if (a.pid == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);  // never outlives a test that crashed
    try {
      dtest::RunningDaemon d(config("pc-a", "routerA"));
      while (shoptest::start_ready_jobs(d.daemon()) == 0) ::usleep(50'000);  // polling the local queue
      ::pause();
    } catch (...) {
      ::_exit(1);
    }
    ::_exit(0);
  }
  const auto job_row = [&] {
    return admin.exec("SELECT j.status, j.last_line, j.message, m.name FROM shop.jobs j"
                      " LEFT JOIN shop.machines m ON m.id = j.machine_id WHERE j.id = $1",
                      {std::to_string(job)});
  };
  ASSERT_TRUE(dtest::wait_for([&] {
    const auto r = job_row();
    return r.text(0, 0) == "running" && r.text(0, 3) == "routerA";
  }, 20)) << "routerA should claim and run the job; it is " << job_row().text(0, 0);

  // Daemon B, with an idle machine that can do the job, joins and heart-beats.
  dtest::RunningDaemon b(config("pc-b", "routerB"));
  ASSERT_TRUE(dtest::wait_for([&] {
    return admin.exec("SELECT count(*) FROM shop.machine_state s JOIN shop.machines m ON m.id = s.machine_id"
                      " WHERE m.name = 'routerB' AND s.availability = 'AVAILABLE' AND s.execution = 'READY'").i64(0, 0) == 1;
  }, 10)) << "routerB should be up and idle";

  // Mid-job (a few lines reported), A is killed: no goodbye, no last event.
  ASSERT_TRUE(dtest::wait_for([&] { return job_row().i64(0, 1) >= 4; }, 20)) << "the job's line did not advance";
  a.kill9();
  const auto before = job_row();
  ASSERT_EQ(before.text(0, 0), "running") << "the job ended before the kill: make the program longer";
  const std::int64_t last_line = before.i64(0, 1);
  const auto reported = admin.exec(
      "SELECT coalesce(max(greatest((e.body->>'line')::bigint, (e.body->>'last_line')::bigint)), 0)"
      " FROM shop.job_events e WHERE e.job_id = $1", {std::to_string(job)});
  EXPECT_EQ(reported.i64(0, 0), last_line) << "the hub's last line is the highest line A reported";

  // After the lease (2 s), B's heartbeat sweeps it: interrupted, on A, at A's last line.
  const auto t_kill = std::chrono::steady_clock::now();
  ASSERT_TRUE(dtest::wait_for([&] { return job_row().text(0, 0) == "interrupted"; }, 10))
      << "the lapsed lease did not interrupt the job";
  EXPECT_GE(std::chrono::steady_clock::now() - t_kill, std::chrono::milliseconds(1000))
      << "interrupted before its lease could lapse";
  const auto after = job_row();
  EXPECT_EQ(after.i64(0, 1), last_line);
  EXPECT_EQ(after.text(0, 3), "routerA");
  EXPECT_NE(after.text(0, 2).find("last reported line " + std::to_string(last_line)), std::string::npos)
      << after.text(0, 2);

  // B goes on claiming (a new job reaches it) but never the interrupted one,
  // though it is older: only an operator requeues it.
  shop::Submission next = s;
  next.file_name = "next.nc";
  next.content = shoptest::tiny_program(1);
  const std::int64_t next_job = hub.submit_job(next);
  ASSERT_TRUE(dtest::wait_for([&] {
    return admin.exec("SELECT count(*) FROM shop.jobs j JOIN shop.machines m ON m.id = j.machine_id"
                      " WHERE j.id = $1 AND m.name = 'routerB' AND j.status = 'awaiting_operator'",
                      {std::to_string(next_job)}).i64(0, 0) == 1;
  }, 10)) << "routerB did not claim the new job";
  const auto still = job_row();
  EXPECT_EQ(still.text(0, 0), "interrupted");
  EXPECT_EQ(still.text(0, 3), "routerA");
  const auto local = shoptest::on_loop(b.daemon(), [&] { return b.daemon().jobs().list(std::nullopt, std::nullopt); });
  ASSERT_EQ(local["jobs"].size(), 1u) << local.dump();
  EXPECT_EQ(local["jobs"][0]["file_name"], "next.nc");
  EXPECT_EQ(admin.exec("SELECT count(*) FROM shop.job_events e JOIN shop.machines m ON m.id = e.machine_id"
                       " WHERE m.name = 'routerB' AND e.kind = 'job' AND e.body->>'state' = 'running'").i64(0, 0), 0);
  b.shutdown();
  std::error_code ec;
  fs::remove_all(dir, ec);
}
