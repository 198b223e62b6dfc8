// The shop view pushed (docs/shop.md, "The shop view"): a machine's change
// reported by one daemon reaches a WebSocket client of another as a `shop`
// frame, through the hub's NOTIFY (migration 3) and not any poll (the
// daemons push nothing without a wake-up); the listener comes back after
// the hub restarts.
#include <gtest/gtest.h>

#include "cncstream/daemon/shop_watch.hpp"
#include "cncstream/shop/hub.hpp"
#include "cncstream/shop/schema.hpp"
#include "shop_daemon_util.hpp"
#include "shop_test_util.hpp"

using namespace cncstream;
namespace fs = std::filesystem;
using shop::PgConnection;
using nlohmann::json;

namespace {

shop::Submission live_job(const std::string& name, const std::string& machine) {
  shop::Submission s;
  s.file_name = name;
  s.kind = "gcode";
  s.content = shoptest::tiny_program(2);
  s.machine = machine;
  return s;
}

// The machine's entry in a `shop` frame (null when absent).
json machine_in(const json& frame, const std::string& name) {
  for (const auto& m : frame.value("machines", json::array()))
    if (m.value("name", "") == name) return m;
  return nullptr;
}

bool changed_has(const json& frame, const std::string& what) {
  for (const auto& c : frame.value("changed", json::array()))
    if (c == what) return true;
  return false;
}

}  // namespace

TEST(ShopLive, AChangeOnOnePcReachesAnotherPcsWebSocketAtOnceAndAfterTheHubRestarts) {
  SHOP_REQUIRE_POSTGRES();
  shoptest::TempPostgres pg;
  pg.create_database("live");
  PgConnection admin(pg.url("live"));
  shop::migrate(admin);
  admin.exec("CREATE ROLE pc_live LOGIN IN ROLE cncstream_pc");
  const std::string pc_url = pg.url("live", "pc_live");
  const fs::path dir = dtest::temp_dir("shop-live");
  dtest::RunningDaemon a(shoptest::shop_daemon_config(dir / "pca", pc_url, {dtest::sim_machine("a1")}));
  dtest::RunningDaemon b(shoptest::shop_daemon_config(dir / "pcb", pc_url, {dtest::sim_machine("b1")}));
  auto* watch = b.daemon().shop_watch();
  ASSERT_NE(watch, nullptr);
  ASSERT_TRUE(dtest::wait_for([&] {
    return watch->listening() &&
           admin.exec("SELECT count(*) FROM shop.machine_state WHERE availability = 'AVAILABLE'").i64(0, 0) == 2;
  }, 20));

  dtest::WsClient ws;
  ASSERT_EQ(ws.connect(b.port(), "/api/v1/ws?client_id=live"), 101);
  // Quiet first: the registrations' frames are read away.
  while (ws.recv(0.5)) {
  }

  // A job for a1 (on the other PC): claimed, its program loaded, waiting for
  // the operator. B's client sees it through the hub, well before the page's
  // 5 s poll; nothing but the hub's notification makes B send the frame.
  shop::Hub hub(admin);
  const auto job = hub.submit_job(live_job("live.nc", "a1"));
  const auto t0 = std::chrono::steady_clock::now();
  const auto seen = ws.wait_message([&](const json& f) {
    if (f.value("type", "") != "shop") return false;
    const json m = machine_in(f, "a1");
    return m.is_object() && m["job"].is_object() && m["job"]["id"] == job &&
           m["job"]["status"] == "awaiting_operator" && m["state"]["program"] == "live.nc";
  }, 10);
  ASSERT_TRUE(seen) << "no shop frame showed a1's claimed job";
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(4))
      << "the claim, the report and the push took longer than the fallback poll";
  EXPECT_FALSE((*seen)["resync"].get<bool>());
  // The frame carries what changed, not the whole shop: a1's row and the
  // job itself as the view's job list shows it; b1 did not change.
  EXPECT_TRUE(machine_in(*seen, "b1").is_null()) << seen->dump();
  const auto job_in = [](const json& frame, std::int64_t id) {
    for (const auto& j : frame.value("jobs", json::array()))
      if (j.value("id", std::int64_t{0}) == id) return j;
    return json(nullptr);
  };
  json pushed = job_in(*seen, job);  // the same frame, or a later one
  if (!pushed.is_object() || pushed["status"] != "awaiting_operator") {
    const auto seen_job = ws.wait_message([&](const json& f) {
      const json j = job_in(f, job);
      return f.value("type", "") == "shop" && j.is_object() && j["status"] == "awaiting_operator";
    }, 10);
    ASSERT_TRUE(seen_job) << "no shop frame carried the job awaiting its operator";
    pushed = job_in(*seen_job, job);
  }
  EXPECT_EQ(pushed["machine"], "a1");
  EXPECT_EQ(pushed["file_name"], "live.nc");
  EXPECT_FALSE(pushed.contains("content")) << "a frame never carries a job's file";

  // The hub restarted: the listener LISTENs again by itself (a resync frame
  // says so), and the next change is pushed again.
  pg.stop();
  EXPECT_TRUE(dtest::wait_for([&] { return !watch->listening(); }, 10));
  pg.start();
  const auto resync = ws.wait_message([](const json& f) { return f.value("type", "") == "shop" && f.value("resync", false); }, 15);
  ASSERT_TRUE(resync) << "no frame after the hub came back";
  EXPECT_TRUE((*resync)["machines"].empty()) << "a resync frame asks the page to read the whole view";
  EXPECT_TRUE(watch->listening());
  while (ws.recv(0.3)) {  // what A's reconnection ships
  }
  // The operator runs it on a1: completed, and a1 free again.
  ASSERT_TRUE(dtest::wait_for([&] { return shoptest::start_ready_jobs(a.daemon()) == 1; }, 10));
  const auto done = ws.wait_message([&](const json& f) {
    if (f.value("type", "") != "shop" || f.value("resync", false)) return false;
    const json m = machine_in(f, "a1");
    const json j = job_in(f, job);
    return changed_has(f, "job:" + std::to_string(job)) && m.is_object() && m["job"].is_null() && j.is_object() &&
           j["status"] == "completed";
  }, 10);
  ASSERT_TRUE(done) << "the finished job was not pushed after the hub restarted";
  PgConnection admin_again(pg.url("live"));  // the restart closed the first
  EXPECT_EQ(admin_again.exec("SELECT status FROM shop.jobs WHERE id = $1", {std::to_string(job)}).text(0, 0), "completed");
  b.shutdown();
  a.shutdown();
  std::error_code ec;
  fs::remove_all(dir, ec);
}

// Migration 3's triggers: one notification per change, at commit, none for
// what the view does not show (a heartbeat of a machine whose state is the same).
TEST(ShopLive, TheHubNotifiesStateAndJobChangesOnly) {
  SHOP_REQUIRE_POSTGRES();
  shoptest::TempPostgres pg;
  const std::string url = pg.create_database("notify");
  PgConnection admin(url);
  shop::migrate(admin);
  PgConnection listener(url);
  listener.exec("LISTEN cncstream_state");
  shop::Hub hub(admin);
  shop::MachineInfo info;
  info.name = "n1";
  shop::MachineState st;
  hub.heartbeat(info, st, 30);
  // What arrived up to a marker sent now (notifications come in commit order).
  auto take = [&] {
    admin.exec("NOTIFY cncstream_state, 'marker'");
    std::vector<std::string> out;
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (std::chrono::steady_clock::now() < end) {
      for (auto& n : listener.take_notifications()) {
        if (n.payload == "marker") return out;
        out.push_back(n.payload);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ADD_FAILURE() << "the marker never came";
    return out;
  };
  EXPECT_EQ(take(), (std::vector<std::string>{"machine:n1"}));
  hub.heartbeat(info, st, 30);
  EXPECT_TRUE(take().empty()) << "a heartbeat that changes nothing shown notifies nothing";
  st.path_position = std::array<double, 3>{1, 2, 3};
  hub.heartbeat(info, st, 30);
  EXPECT_TRUE(take().empty()) << "the position alone does not wake the shop";
  st.execution = "ACTIVE";
  hub.heartbeat(info, st, 30);
  EXPECT_EQ(take(), (std::vector<std::string>{"machine:n1"}));
  const auto id = hub.submit_job(live_job("n.nc", ""));
  EXPECT_EQ(take(), (std::vector<std::string>{"job:" + std::to_string(id)}));
  ASSERT_TRUE(hub.claim_job("n1", 30));
  EXPECT_EQ(take(), (std::vector<std::string>{"job:" + std::to_string(id)}));
  EXPECT_GE(shop::hub_schema_version(admin), 3);
}
