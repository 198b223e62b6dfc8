// The shop view (docs/shop.md): any daemon in a shop serves every machine of
// every PC, the queue and history with filters and a job's events, read from
// the hub with a PC's login; the hub down gives 503 and the rest of the
// daemon answers on.
#include <gtest/gtest.h>

#include <future>
#include <set>

#include "cncstream/shop/hub.hpp"
#include "cncstream/shop/schema.hpp"
#include "cncstream/shop/shop_view.hpp"
#include "shop_daemon_util.hpp"
#include "shop_test_util.hpp"

using namespace cncstream;
namespace fs = std::filesystem;
using shop::PgConnection;
using nlohmann::json;

namespace {

shop::Submission view_job(const std::string& name, std::vector<std::string> needs, std::string machine = "") {
  shop::Submission s;
  s.file_name = name;
  s.kind = "gcode";
  s.content = shoptest::tiny_program(1);
  s.needs = std::move(needs);
  s.machine = std::move(machine);
  return s;
}

daemon::MachineConfig view_machine(const std::string& name, std::vector<std::string> caps = {}) {
  auto m = dtest::sim_machine(name);
  m.capabilities = std::move(caps);
  return m;
}

std::set<std::string> ids_of(const json& jobs) {
  std::set<std::string> out;
  for (const auto& j : jobs) out.insert(j.at("file_name").get<std::string>());
  return out;
}

}  // namespace

TEST(ShopView, ADaemonServesEveryPcsMachinesTheJobsWithFiltersAndAJobsEvents) {
  SHOP_REQUIRE_POSTGRES();
  shoptest::TempPostgres pg;
  pg.create_database("view");
  PgConnection admin(pg.url("view"));
  shop::migrate(admin);
  // The daemons use a PC's login, which reads no table: the view goes through its functions.
  admin.exec("CREATE ROLE pc_view LOGIN IN ROLE cncstream_pc");
  const std::string pc_url = "postgresql://pc_view:s3cret-word@127.0.0.1:" + std::to_string(pg.port()) + "/view";
  const fs::path dir = dtest::temp_dir("shop-view");
  auto config_a = shoptest::shop_daemon_config(dir / "pca", pc_url, {view_machine("a1", {"vacuum"})});
  config_a.security.require_token = true;
  dtest::RunningDaemon a(config_a);
  dtest::RunningDaemon b(shoptest::shop_daemon_config(dir / "pcb", pc_url, {view_machine("b1"), view_machine("b2")}));
  dtest::Http http = a.http;
  // Beyond loopback (here: a token required) the shop view needs the token like every route.
  EXPECT_EQ(http.get("/api/v1/shop/machines").status, 401);
  EXPECT_EQ(http.get("/api/v1/shop").status, 401);
  http.headers["Authorization"] = "Bearer " + a.daemon().token();

  // A job for a named machine needs it registered (its first heartbeat).
  ASSERT_TRUE(dtest::wait_for([&] {
    return admin.exec("SELECT count(*) FROM shop.machine_state WHERE availability = 'AVAILABLE'").i64(0, 0) == 3;
  }, 20));
  shop::Hub hub(admin);
  hub.submit_job(view_job("vac.nc", {"vacuum"}));   // only a1 can
  hub.submit_job(view_job("b1.nc", {}, "b1"));      // only b1
  hub.submit_job(view_job("laser.nc", {"laser"}));  // nobody: stays pending
  ASSERT_TRUE(dtest::wait_for([&] {
    return admin.exec("SELECT count(*) FROM shop.jobs WHERE status = 'awaiting_operator'").i64(0, 0) == 2;
  }, 20));

  const auto member = http.get("/api/v1/shop");
  ASSERT_EQ(member.status, 200) << member.body;
  EXPECT_TRUE(member.j()["member"].get<bool>());
  EXPECT_EQ(member.j()["hub"].get<std::string>().find("s3cret"), std::string::npos) << member.body;

  // Every machine of every PC, with its state in MTConnect's words and its heartbeat's age.
  const auto machines = http.get("/api/v1/shop/machines");
  ASSERT_EQ(machines.status, 200) << machines.body;
  std::map<std::string, json> by_name;
  const json machines_body = machines.j();
  for (const auto& m : machines_body["machines"]) by_name[m["name"].get<std::string>()] = m;
  ASSERT_EQ(by_name.size(), 3u) << machines.body;
  EXPECT_EQ(by_name["b2"]["pc"], "pcb");
  EXPECT_EQ(by_name["a1"]["pc"], "pca");
  EXPECT_EQ(by_name["b2"]["state"]["availability"], "AVAILABLE");
  EXPECT_EQ(by_name["b2"]["state"]["execution"], "READY");
  EXPECT_LT(by_name["b2"]["heartbeat_age_s"].get<double>(), 5.0);
  EXPECT_EQ(by_name["a1"]["capabilities"], json::array({"vacuum"}));
  EXPECT_EQ(by_name["b1"]["job"]["file_name"], "b1.nc");
  EXPECT_EQ(by_name["b1"]["job"]["status"], "awaiting_operator");
  EXPECT_TRUE(by_name["b2"]["job"].is_null());

  // The queue and history, filtered.
  const auto all = http.get("/api/v1/shop/jobs");
  ASSERT_EQ(all.status, 200) << all.body;
  EXPECT_EQ(ids_of(all.j()["jobs"]), (std::set<std::string>{"vac.nc", "b1.nc", "laser.nc"}));
  EXPECT_EQ(all.j()["jobs"][0]["file_name"], "laser.nc") << "newest first";
  EXPECT_FALSE(all.j()["jobs"][0].contains("content")) << "a job's file never travels in the view";
  EXPECT_EQ(all.j()["counts"]["pending"], 1);
  EXPECT_EQ(all.j()["counts"]["awaiting_operator"], 2);
  EXPECT_EQ(ids_of(http.get("/api/v1/shop/jobs?status=pending").j()["jobs"]), (std::set<std::string>{"laser.nc"}));
  EXPECT_EQ(ids_of(http.get("/api/v1/shop/jobs?machine=b1").j()["jobs"]), (std::set<std::string>{"b1.nc"}));
  EXPECT_EQ(ids_of(http.get("/api/v1/shop/jobs?machine=a1&status=awaiting_operator,running").j()["jobs"]),
            (std::set<std::string>{"vac.nc"}));
  const auto one = http.get("/api/v1/shop/jobs?limit=1").j();
  ASSERT_EQ(one["jobs"].size(), 1u);
  EXPECT_EQ(ids_of(http.get("/api/v1/shop/jobs?before=" + std::to_string(one["jobs"][0]["id"].get<long>())).j()["jobs"]),
            (std::set<std::string>{"vac.nc", "b1.nc"}));
  const auto bad_status = http.get("/api/v1/shop/jobs?status=done");
  EXPECT_EQ(bad_status.status, 400);
  EXPECT_NE(bad_status.body.find("'done' is not a shop job's status"), std::string::npos) << bad_status.body;
  EXPECT_EQ(http.get("/api/v1/shop/jobs?machine=no%20such").status, 400);
  EXPECT_EQ(http.get("/api/v1/shop/jobs?limit=0").status, 400);

  // A job run on the other PC: its events, as B's journal shipped them.
  const long b1_job = by_name["b1"]["job"]["id"].get<long>();
  ASSERT_TRUE(dtest::wait_for([&] {
    shoptest::start_ready_jobs(b.daemon());
    return http.get("/api/v1/shop/jobs?status=completed&machine=b1").j()["jobs"].size() == 1;
  }, 20));
  const auto events = http.get("/api/v1/shop/jobs/" + std::to_string(b1_job) + "/events");
  ASSERT_EQ(events.status, 200) << events.body;
  EXPECT_EQ(events.j()["job"]["status"], "completed");
  EXPECT_EQ(events.j()["job"]["machine"], "b1");
  std::vector<std::string> states;
  const json events_body = events.j();
  for (const auto& e : events_body["events"]) {
    EXPECT_EQ(e["machine"], "b1");
    if (e["kind"] == "job") states.push_back(e["body"]["state"].get<std::string>());
  }
  EXPECT_NE(std::find(states.begin(), states.end(), "running"), states.end()) << events.body;
  EXPECT_EQ(states.back(), "done") << events.body;
  const auto none = http.get("/api/v1/shop/jobs/999999/events");
  EXPECT_EQ(none.status, 404);
  EXPECT_NE(none.body.find("no job 999999"), std::string::npos) << none.body;

  // The hub stopped: the view says so at once, naming the hub without its
  // password; the daemon's own API answers on.
  pg.stop();
  const auto t0 = std::chrono::steady_clock::now();
  const auto down = http.get("/api/v1/shop/machines");
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(4));
  EXPECT_EQ(down.status, 503) << down.body;
  EXPECT_EQ(down.j()["error"]["code"], "hub_unavailable");
  const std::string msg = down.j()["error"]["message"];
  EXPECT_NE(msg.find("127.0.0.1"), std::string::npos) << msg;
  EXPECT_EQ(msg.find("s3cret"), std::string::npos) << msg;
  EXPECT_EQ(http.get("/api/v1/shop/jobs").status, 503);
  EXPECT_EQ(http.get("/api/v1/machines").status, 200);
  EXPECT_EQ(http.get("/api/v1/jobs").status, 200);
  // Back: the view reconnects by itself.
  pg.start();
  EXPECT_TRUE(dtest::wait_for([&] { return http.get("/api/v1/shop/machines").status == 200; }, 10));
  b.shutdown();
  a.shutdown();
  std::error_code ec;
  fs::remove_all(dir, ec);
}

TEST(ShopView, ADaemonOutsideAShopSaysSo) {
  const fs::path dir = dtest::temp_dir("shop-view-none");
  dtest::RunningDaemon d(dtest::test_config(dir));
  const auto member = d.http.get("/api/v1/shop");
  ASSERT_EQ(member.status, 200);
  EXPECT_FALSE(member.j()["member"].get<bool>());
  for (const char* path : {"/api/v1/shop/machines", "/api/v1/shop/jobs", "/api/v1/shop/jobs/1/events"}) {
    const auto r = d.http.get(path);
    EXPECT_EQ(r.status, 409) << path;
    EXPECT_NE(r.body.find("not_in_shop"), std::string::npos) << path << ": " << r.body;
  }
  for (const char* path : {"/api/v1/shop/jobs", "/api/v1/shop/jobs/1/cancel", "/api/v1/shop/jobs/1/requeue"}) {
    const auto r = d.http.post(path, {{"file", std::string(64, 'a')}, {"on", "any_machine"}});
    EXPECT_EQ(r.status, 409) << path;
    EXPECT_NE(r.body.find("not_in_shop"), std::string::npos) << path << ": " << r.body;
  }
  d.shutdown();
  std::error_code ec;
  fs::remove_all(dir, ec);
}

// A hub migrated by an older program (no shop.view_*): the view says what to
// run, instead of PostgreSQL's "function does not exist".
TEST(ShopView, AHubWithoutTheViewFunctionsAsksForShopInit) {
  SHOP_REQUIRE_POSTGRES();
  shoptest::TempPostgres pg;
  const std::string url = pg.create_database("old");
  {
    PgConnection admin(url);
    admin.exec(shop::migrations().front().sql);  // version 1 only
  }
  shop::ShopViewReader reader(url);
  std::promise<shop::ViewAnswer> answer;
  reader.submit([](PgConnection& db) -> std::optional<json> { return shop::view_machines(db); },
                [&](shop::ViewAnswer a) { answer.set_value(std::move(a)); });
  const auto a = answer.get_future().get();
  EXPECT_EQ(a.kind, shop::ViewAnswer::Kind::hub_unavailable);
  EXPECT_NE(a.message.find("cncstream shop init"), std::string::npos) << a.message;
}
