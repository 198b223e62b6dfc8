// Daemons in a shop: claiming from one queue, the outbox through a hub
// outage, against a throw-away PostgreSQL.
#include <gtest/gtest.h>

#include <map>
#include <set>

#include "cncstream/shop/hub.hpp"
#include "cncstream/shop/schema.hpp"
#include "shop_daemon_util.hpp"
#include "shop_test_util.hpp"

using namespace cncstream;
namespace fs = std::filesystem;
using shop::PgConnection;

namespace {

shop::Submission job(int i, std::vector<std::string> needs = {}) {
  shop::Submission s;
  s.file_name = "part" + std::to_string(i) + ".nc";
  s.kind = "gcode";
  s.content = shoptest::tiny_program(i);
  s.needs = std::move(needs);
  return s;
}

daemon::MachineConfig machine(const std::string& name, std::vector<std::string> caps = {}) {
  auto m = dtest::sim_machine(name);
  m.capabilities = std::move(caps);
  return m;
}

// Checks every machine's events on the hub: each sequence once, 1..n without a gap.
void expect_no_gaps(PgConnection& db) {
  const auto r = db.exec("SELECT m.name, count(*), count(DISTINCT e.seq), min(e.seq), max(e.seq)"
                         " FROM shop.job_events e JOIN shop.machines m ON m.id = e.machine_id GROUP BY m.name");
  EXPECT_GT(r.rows(), 0);
  for (int i = 0; i < r.rows(); ++i) {
    EXPECT_EQ(r.i64(i, 1), r.i64(i, 2)) << r.text(i, 0) << ": an event stored twice";
    EXPECT_EQ(r.i64(i, 3), 1) << r.text(i, 0);
    EXPECT_EQ(r.i64(i, 4), r.i64(i, 1)) << r.text(i, 0) << ": a gap in the sequence";
  }
}

}  // namespace

// Four daemons with two simulated machines each take jobs from one queue:
// a claimed job waits for the operator; every job runs exactly once, on a
// machine that can do it.
TEST(ShopDaemons, FourDaemonsRunEveryJobOfOneQueueOnceOnACapableMachine) {
  SHOP_REQUIRE_POSTGRES();
  shoptest::TempPostgres pg;
  const std::string url = pg.create_database("daemons");
  PgConnection admin(url);
  shop::migrate(admin);
  shop::Hub hub(admin);
  const fs::path dir = dtest::temp_dir("shop-daemons");
  std::vector<std::unique_ptr<dtest::RunningDaemon>> daemons;
  for (int d = 0; d < 4; ++d) {
    const std::string a = "d" + std::to_string(d) + "a", b = "d" + std::to_string(d) + "b";
    daemons.push_back(std::make_unique<dtest::RunningDaemon>(shoptest::shop_daemon_config(
        dir / ("pc" + std::to_string(d)), url, {machine(a), machine(b, d % 2 ? std::vector<std::string>{"vacuum"} : std::vector<std::string>{})})));
  }
  // Nothing is started by itself: the first claims wait for the operator.
  constexpr int kJobs = 32;
  for (int i = 0; i < kJobs; ++i) hub.submit_job(job(i, i % 4 == 1 ? std::vector<std::string>{"vacuum"} : std::vector<std::string>{}));
  ASSERT_TRUE(dtest::wait_for([&] {
    return admin.exec("SELECT count(*) FROM shop.jobs WHERE status = 'awaiting_operator'").i64(0, 0) == 8;
  }, 20)) << "each machine should hold one job awaiting its operator";
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  EXPECT_EQ(admin.exec("SELECT count(*) FROM shop.jobs WHERE status NOT IN ('pending', 'awaiting_operator')").i64(0, 0), 0);
  // The operators start what waits, until the queue is empty.
  const bool all_done = dtest::wait_for([&] {
    for (auto& d : daemons) shoptest::start_ready_jobs(d->daemon());
    return admin.exec("SELECT count(*) FROM shop.jobs WHERE status = 'completed'").i64(0, 0) == kJobs;
  }, 60);
  const auto st = admin.exec("SELECT status, count(*) FROM shop.jobs GROUP BY status ORDER BY 1");
  std::string summary;
  for (int i = 0; i < st.rows(); ++i) summary += st.text(i, 0) + "=" + st.text(i, 1) + " ";
  ASSERT_TRUE(all_done) << summary;
  // Each job started once (one 'running' event), on a machine with what it needs.
  const auto runs = admin.exec(
      "SELECT j.id, count(*), min(m.name), bool_and(j.needs <@ m.capabilities) FROM shop.job_events e"
      " JOIN shop.jobs j ON j.id = e.job_id JOIN shop.machines m ON m.id = e.machine_id"
      " WHERE e.kind = 'job' AND e.body->>'state' = 'running' GROUP BY j.id");
  EXPECT_EQ(runs.rows(), kJobs);
  std::set<std::string> machines_used;
  for (int i = 0; i < runs.rows(); ++i) {
    EXPECT_EQ(runs.i64(i, 1), 1) << "job " << runs.i64(i, 0) << " ran " << runs.i64(i, 1) << " times";
    EXPECT_EQ(runs.text(i, 3), "t") << "job " << runs.i64(i, 0) << " ran on " << runs.text(i, 2) << " without its needs";
    machines_used.insert(runs.text(i, 2));
  }
  EXPECT_GE(machines_used.size(), 6u) << "the queue should spread over the machines";
  // The machines reported their state in MTConnect's words.
  EXPECT_EQ(admin.exec("SELECT count(*) FROM shop.machine_state WHERE availability = 'AVAILABLE'").i64(0, 0), 8);
  daemons.clear();
  expect_no_gaps(admin);
  std::error_code ec;
  fs::remove_all(dir, ec);
}

// The hub goes down for a few seconds while the machines run jobs: the
// daemon keeps running them (the local queue), claiming pauses, and when the
// hub is back every event arrives once, in order, with no gap.
TEST(ShopDaemons, AHubOutageLosesNoEventAndOnlyPausesClaiming) {
  SHOP_REQUIRE_POSTGRES();
  shoptest::TempPostgres pg;
  const std::string url = pg.create_database("outage");
  {
    PgConnection admin(url);
    shop::migrate(admin);
    shop::Hub hub(admin);
    for (int i = 0; i < 4; ++i) hub.submit_job(job(i));
  }
  const fs::path dir = dtest::temp_dir("shop-outage");
  dtest::RunningDaemon d(shoptest::shop_daemon_config(dir / "pc", url, {machine("r1"), machine("r2")}));
  auto& link = *d.daemon().shop();
  const auto count = [&](const char* state) {
    return shoptest::on_loop(d.daemon(), [&] { return d.daemon().jobs().list(std::nullopt, std::string(state))["jobs"].size(); });
  };
  ASSERT_TRUE(dtest::wait_for([&] { return count("ready") == 2; }, 20)) << "each machine should claim one job";
  pg.stop();
  ASSERT_TRUE(dtest::wait_for([&] { return !link.client().hub_up(); }, 10));
  const auto t_down = std::chrono::steady_clock::now();
  // The operator runs the two shop jobs while the hub is away.
  int started = 0;
  ASSERT_TRUE(dtest::wait_for([&] {
    started += shoptest::start_ready_jobs(d.daemon());
    return started == 2;
  }, 10));
  ASSERT_TRUE(dtest::wait_for([&] { return count("done") == 2; }, 15)) << "the machines stopped with the hub";
  // Nothing is claimed while the hub is away: the machines stay free.
  std::this_thread::sleep_until(t_down + std::chrono::seconds(4));
  EXPECT_EQ(count("ready"), 0u);
  EXPECT_GT(link.client().unsent(), 0);
  EXPECT_FALSE(link.client().hub_up());
  pg.start();
  ASSERT_TRUE(dtest::wait_for([&] { return link.client().hub_up() && link.client().unsent() == 0; }, 20));
  PgConnection admin(url);
  EXPECT_EQ(admin.exec("SELECT count(*) FROM shop.jobs WHERE status = 'completed'").i64(0, 0), 2);
  expect_no_gaps(admin);
  // Claiming resumes: the other two jobs wait at the machines.
  EXPECT_TRUE(dtest::wait_for([&] {
    return admin.exec("SELECT count(*) FROM shop.jobs WHERE status = 'awaiting_operator'").i64(0, 0) == 2;
  }, 10));
  d.shutdown();
  std::error_code ec;
  fs::remove_all(dir, ec);
}
