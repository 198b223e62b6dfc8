// The operator's acts from a daemon's web page (docs/api-v1.md, "Shop"):
// submit, cancel and requeue through the hub's functions, under a PC's login
// that was granted cncstream_web_operator, and refused with the hub's words.
#include <gtest/gtest.h>

#include "cncstream/shop/hub.hpp"
#include "cncstream/shop/schema.hpp"
#include "shop_daemon_util.hpp"
#include "shop_test_util.hpp"

using namespace cncstream;
namespace fs = std::filesystem;
using nlohmann::json;
using shop::PgConnection;

namespace detail_shop_acts {

std::string upload(const dtest::Http& http, const std::string& name, const std::string& bytes) {
  const auto r = http.request("POST", "/api/v1/files?name=" + name, bytes, {{"Content-Type", "application/octet-stream"}});
  if (r.status != 201 && r.status != 200) throw std::runtime_error("upload " + name + ": " + r.body);
  return r.j()["id"].get<std::string>();
}

constexpr const char* kTriangle =
    "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 20 0 0\nvertex 0 20 5\nendloop\nendfacet\nendsolid t\n";

}  // namespace detail_shop_acts

TEST(ShopActs, ThePageSubmitsCancelsAndRequeuesThroughTheHubUnderAGrantedPcLogin) {
  SHOP_REQUIRE_POSTGRES();
  using detail_shop_acts::upload;
  shoptest::TempPostgres pg;
  pg.create_database("acts");
  PgConnection admin(pg.url("acts"));
  shop::migrate(admin);
  admin.exec("CREATE ROLE pc_web LOGIN IN ROLE cncstream_pc");
  const fs::path dir = dtest::temp_dir("shop-acts");
  auto m = dtest::sim_machine("w1");
  m.shop_claim = false;  // the jobs stay in the queue for the test to act on
  auto config = shoptest::shop_daemon_config(dir / "pc", pg.url("acts", "pc_web"), {m});
  config.security.require_token = true;
  dtest::RunningDaemon d(config);
  dtest::Http http = d.http;
  const std::string program = shoptest::tiny_program(2);
  // Beyond loopback (a token required) the acts need the token like every route.
  EXPECT_EQ(http.post("/api/v1/shop/jobs", {{"file", std::string(64, 'a')}}).status, 401);
  http.headers["Authorization"] = "Bearer " + d.daemon().token();
  const std::string nc = upload(http, "part.nc", program);
  ASSERT_TRUE(dtest::wait_for([&] { return admin.exec("SELECT count(*) FROM shop.machines WHERE name = 'w1'").i64(0, 0) == 1; }, 10));

  // A PC's login alone may not submit: the hub refuses, the daemon says what to grant.
  const auto forbidden = http.post("/api/v1/shop/jobs", {{"file", nc}});
  EXPECT_EQ(forbidden.status, 403) << forbidden.body;
  EXPECT_EQ(forbidden.j()["error"]["code"], "hub_forbidden");
  EXPECT_NE(forbidden.body.find("cncstream_web_operator"), std::string::npos) << forbidden.body;
  admin.exec("GRANT cncstream_web_operator TO pc_web");

  // Submitted: on the hub as the PC's login, with its machine and needs and the file's bytes.
  const auto sub = http.post("/api/v1/shop/jobs", {{"file", nc}, {"machine", "w1"}, {"needs", {"vacuum"}}});
  ASSERT_EQ(sub.status, 201) << sub.body;
  const std::int64_t id = sub.j()["id"].get<std::int64_t>();
  EXPECT_EQ(sub.j()["status"], "pending");
  const auto row = admin.exec("SELECT status, machine, needs::text, submitted_by, convert_from(content, 'UTF8'), kind, file_name"
                              " FROM shop.jobs WHERE id = $1", {std::to_string(id)});
  EXPECT_EQ(row.text(0, 0), "pending");
  EXPECT_EQ(row.text(0, 1), "w1");
  EXPECT_EQ(row.text(0, 2), "{vacuum}");
  EXPECT_EQ(row.text(0, 3), "pc_web");
  EXPECT_EQ(row.text(0, 4), program);
  EXPECT_EQ(row.text(0, 5), "gcode");
  EXPECT_EQ(row.text(0, 6), "part.nc");

  // An STL goes with its cutter's spec, checked here as the claiming daemon will check it.
  const std::string stl = upload(http, "tri.stl", detail_shop_acts::kTriangle);
  const auto no_tool = http.post("/api/v1/shop/jobs", {{"file", stl}});
  EXPECT_EQ(no_tool.status, 400);
  EXPECT_NE(no_tool.body.find("tool"), std::string::npos) << no_tool.body;
  EXPECT_EQ(http.post("/api/v1/shop/jobs", {{"file", stl}, {"params", {{"tool", 3}}}}).status, 400);
  const auto bad_tool = http.post("/api/v1/shop/jobs", {{"file", stl}, {"params", {{"tool", "spoon:3"}}}});
  EXPECT_EQ(bad_tool.status, 400) << bad_tool.body;
  const auto part = http.post("/api/v1/shop/jobs", {{"file", stl}, {"params", {{"tool", "ball:3.175"}}}});
  ASSERT_EQ(part.status, 201) << part.body;
  EXPECT_EQ(admin.exec("SELECT kind, params->>'tool' FROM shop.jobs WHERE id = $1",
                       {std::to_string(part.j()["id"].get<std::int64_t>())}).text(0, 1), "ball:3.175");

  // Bad submissions: each names what is wrong.
  const auto expect_error = [&](const json& body, int status, const std::string& words) {
    const auto r = http.post("/api/v1/shop/jobs", body);
    EXPECT_EQ(r.status, status) << body.dump() << " -> " << r.body;
    EXPECT_NE(r.body.find(words), std::string::npos) << body.dump() << " -> " << r.body;
  };
  expect_error(json::object(), 400, "file: required");
  expect_error({{"file", std::string(64, 'b')}}, 404, "no uploaded file");
  expect_error({{"file", nc}, {"machine", "no such"}}, 400, "not a machine name");
  expect_error({{"file", nc}, {"machine", "ghost"}}, 409, "no machine named ghost");
  expect_error({{"file", nc}, {"needs", "vacuum"}}, 400, "needs:");
  expect_error({{"file", nc}, {"needs", {"two words"}}}, 400, "needs: 'two words'");
  expect_error({{"file", nc}, {"params", {{"tool", "ball:3"}}}}, 400, "only for an STL");

  // Cancelled while it waits; a second cancel is refused with the hub's words.
  const std::string sid = std::to_string(id);
  const auto cancel = http.post("/api/v1/shop/jobs/" + sid + "/cancel");
  ASSERT_EQ(cancel.status, 200) << cancel.body;
  EXPECT_EQ(admin.exec("SELECT status, message FROM shop.jobs WHERE id = $1", {sid}).text(0, 0), "cancelled");
  const auto again = http.post("/api/v1/shop/jobs/" + sid + "/cancel");
  EXPECT_EQ(again.status, 409) << again.body;
  EXPECT_NE(again.body.find("is cancelled"), std::string::npos) << again.body;
  EXPECT_EQ(again.body.find("SQLSTATE"), std::string::npos) << "the hub's words, not libpq's: " << again.body;

  // Requeueing is the operator's explicit choice of where.
  const auto unsaid = http.post("/api/v1/shop/jobs/" + sid + "/requeue");
  EXPECT_EQ(unsaid.status, 400);
  EXPECT_NE(unsaid.body.find("same_machine"), std::string::npos) << unsaid.body;
  EXPECT_EQ(http.post("/api/v1/shop/jobs/" + sid + "/requeue", {{"on", "anywhere"}}).status, 400);
  const auto anywhere = http.post("/api/v1/shop/jobs/" + sid + "/requeue", {{"on", "any_machine"}});
  ASSERT_EQ(anywhere.status, 200) << anywhere.body;
  EXPECT_EQ(admin.exec("SELECT status FROM shop.jobs WHERE id = $1", {sid}).text(0, 0), "pending");
  EXPECT_EQ(http.post("/api/v1/shop/jobs/" + sid + "/requeue", {{"on", "any_machine"}}).status, 409)
      << "a pending job is not requeued";

  // An interrupted job (its PC died on w1) back to the same machine, to resume there.
  shop::Hub(admin).submit_job({"lost.nc", "gcode", program, "", {}, ""});
  const std::string lost = std::to_string(admin.exec("SELECT max(id) FROM shop.jobs").i64(0, 0));
  admin.exec("UPDATE shop.jobs SET status = 'interrupted', last_line = 3, ended_at = now(),"
             " machine_id = (SELECT id FROM shop.machines WHERE name = 'w1') WHERE id = $1", {lost});
  const auto same = http.post("/api/v1/shop/jobs/" + lost + "/requeue", {{"on", "same_machine"}});
  ASSERT_EQ(same.status, 200) << same.body;
  const auto back = admin.exec("SELECT j.status, m.name, j.resume_after_line FROM shop.jobs j"
                               " LEFT JOIN shop.machines m ON m.id = j.resume_machine_id WHERE j.id = $1", {lost});
  EXPECT_EQ(back.text(0, 0), "pending");
  EXPECT_EQ(back.text(0, 1), "w1");
  EXPECT_EQ(back.i64(0, 2), 3) << "a resume after the line it stopped at";
  EXPECT_EQ(http.post("/api/v1/shop/jobs/abc/cancel").status, 404);  // not a job id: no such route

  // The grant adds those three functions only: still no table.
  PgConnection pc(pg.url("acts", "pc_web"));
  EXPECT_THROW(pc.exec("SELECT * FROM shop.jobs"), shop::ShopError);
  EXPECT_EQ(pc.last_sqlstate(), "42501");
  EXPECT_THROW(pc.exec("UPDATE shop.jobs SET status = 'pending'"), shop::ShopError);
  EXPECT_EQ(pc.last_sqlstate(), "42501");
  d.shutdown();
  std::error_code ec;
  fs::remove_all(dir, ec);
}

// A job cancelled on the hub after a machine claimed it leaves that machine's
// local queue (the heartbeat brings the cancellation), so its operator cannot
// start it; the machine is free for the next job.
TEST(ShopActs, AJobCancelledOnTheHubLeavesTheLocalQueueOfTheMachineThatClaimedIt) {
  SHOP_REQUIRE_POSTGRES();
  shoptest::TempPostgres pg;
  pg.create_database("acts2");
  PgConnection admin(pg.url("acts2"));
  shop::migrate(admin);
  admin.exec("CREATE ROLE pc_web LOGIN IN ROLE cncstream_pc, cncstream_web_operator");
  const fs::path dir = dtest::temp_dir("shop-acts2");
  dtest::RunningDaemon d(shoptest::shop_daemon_config(dir / "pc", pg.url("acts2", "pc_web"), {dtest::sim_machine("w1")}));
  const auto local_states = [&] {
    const auto l = shoptest::on_loop(d.daemon(), [&] { return d.daemon().jobs().list(std::nullopt, std::nullopt); });
    std::vector<std::string> out;
    for (const auto& j : l["jobs"]) out.push_back(j["file_name"].get<std::string>() + ":" + j["state"].get<std::string>());
    return out;
  };
  const std::string nc = detail_shop_acts::upload(d.http, "held.nc", shoptest::tiny_program(4));
  const auto sub = d.http.post("/api/v1/shop/jobs", {{"file", nc}});
  ASSERT_EQ(sub.status, 201) << sub.body;
  const std::string id = std::to_string(sub.j()["id"].get<std::int64_t>());
  ASSERT_TRUE(dtest::wait_for([&] {
    return admin.exec("SELECT status FROM shop.jobs WHERE id = $1", {id}).text(0, 0) == "awaiting_operator";
  }, 15)) << "w1 should claim the job";
  ASSERT_EQ(local_states(), std::vector<std::string>{"held.nc:ready"});
  const auto cancel = d.http.post("/api/v1/shop/jobs/" + id + "/cancel");
  ASSERT_EQ(cancel.status, 200) << cancel.body;
  EXPECT_TRUE(dtest::wait_for([&] { return local_states() == std::vector<std::string>{"held.nc:cancelled"}; }, 10))
      << "the local job stayed: " << testing::PrintToString(local_states());
  EXPECT_EQ(shoptest::start_ready_jobs(d.daemon()), 0);
  EXPECT_EQ(admin.exec("SELECT status FROM shop.jobs WHERE id = $1", {id}).text(0, 0), "cancelled");
  d.shutdown();
  std::error_code ec;
  fs::remove_all(dir, ec);
}
