// A hub that vanishes without closing its connections (a pulled cable, a
// frozen PC: half-open TCP) is noticed within seconds (docs/shop.md, "When
// something goes down"): a proxy between the daemon and the throw-away
// PostgreSQL goes silent, and the daemon reports the hub down (claiming
// paused, the shop view answering 503 naming the hub, the wake-ups' listener
// off) within the bound its settings give: hub_check_s (1) + hub_timeout_s
// (3) + a second of slack. When the proxy forwards again it comes back.
#include <gtest/gtest.h>

#include "cncstream/daemon/shop_watch.hpp"
#include "cncstream/shop/hub.hpp"
#include "cncstream/shop/schema.hpp"
#include "shop_daemon_util.hpp"
#include "shop_test_util.hpp"
#include "silent_proxy.hpp"

using namespace cncstream;
namespace fs = std::filesystem;
using shop::PgConnection;

namespace detail_shop_outage {

double since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace detail_shop_outage

TEST(ShopOutage, AHubThatFallsSilentWithoutClosingIsReportedDownWithinSecondsAndComesBack) {
  SHOP_REQUIRE_POSTGRES();
  using detail_shop_outage::since;
  shoptest::TempPostgres pg;
  pg.create_database("outage");
  PgConnection admin(pg.url("outage"));
  shop::migrate(admin);
  shop::Hub hub(admin);
  shoptest::SilentProxy proxy(pg.port());
  const std::string via_proxy = "postgresql://postgres@127.0.0.1:" + std::to_string(proxy.port()) + "/outage";
  const fs::path dir = dtest::temp_dir("shop-outage");
  dtest::RunningDaemon d(shoptest::shop_daemon_config(dir, via_proxy, {dtest::sim_machine("r1")}));
  auto* watch = d.daemon().shop_watch();
  ASSERT_NE(watch, nullptr);
  const auto shop_info = [&] { return d.http.get("/api/v1/shop").j(); };
  ASSERT_TRUE(dtest::wait_for([&] { return shop_info()["hub_up"] == true && watch->listening(); }, 15))
      << "the daemon should reach the hub through the proxy";
  ASSERT_EQ(d.http.get("/api/v1/shop/machines").status, 200);

  // The hub falls silent: nothing is answered, nothing is closed.
  proxy.set_silent(true);
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_TRUE(dtest::wait_for([&] { return shop_info()["hub_up"] == false; }, 10))
      << "the daemon never noticed the silent hub";
  const double noticed = since(t0);
  EXPECT_LE(noticed, 5.0) << "claiming paused only after " << noticed << " s";
  std::printf("the silent hub was reported down after %.2f s\n", noticed);
  ASSERT_TRUE(dtest::wait_for([&] { return !watch->listening(); }, 10)) << "the listener never noticed";
  EXPECT_LE(since(t0), 5.0) << "the listener noticed only after " << since(t0) << " s";
  const auto t_read = std::chrono::steady_clock::now();
  const auto view = d.http.get("/api/v1/shop/machines");
  EXPECT_LE(since(t_read), 3.5) << "a read of a silent hub must end within the reply time-out";
  EXPECT_EQ(view.status, 503) << view.body;
  EXPECT_EQ(view.j()["error"]["code"], "hub_unavailable") << view.body;
  EXPECT_NE(view.body.find("127.0.0.1:" + std::to_string(proxy.port())), std::string::npos)
      << "the 503 should name the hub: " << view.body;
  // Claiming is paused: a job submitted meanwhile stays in the hub's queue.
  const auto id = hub.submit_job([] {
    shop::Submission s;
    s.file_name = "while-down.nc";
    s.kind = "gcode";
    s.content = shoptest::tiny_program(3);
    return s;
  }());
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  EXPECT_EQ(admin.exec("SELECT status FROM shop.jobs WHERE id = $1", {std::to_string(id)}).text(0, 0), "pending");

  // The hub answers again: the daemon connects, claims and listens again.
  proxy.set_silent(false);
  const auto t1 = std::chrono::steady_clock::now();
  ASSERT_TRUE(dtest::wait_for([&] { return shop_info()["hub_up"] == true; }, 15)) << "the daemon never came back";
  EXPECT_TRUE(dtest::wait_for([&] {
    return admin.exec("SELECT status FROM shop.jobs WHERE id = $1", {std::to_string(id)}).text(0, 0) == "awaiting_operator";
  }, 10)) << "claiming did not resume: the job is "
           << admin.exec("SELECT status FROM shop.jobs WHERE id = $1", {std::to_string(id)}).text(0, 0) << "; locally "
           << shoptest::on_loop(d.daemon(), [&] { return d.daemon().jobs().list(std::nullopt, std::nullopt); }).dump();
  EXPECT_TRUE(dtest::wait_for([&] { return watch->listening(); }, 10)) << "the listener did not come back";
  EXPECT_TRUE(dtest::wait_for([&] { return d.http.get("/api/v1/shop/machines").status == 200; }, 10));
  EXPECT_LE(since(t1), 12.0);
  d.shutdown();
  std::error_code ec;
  fs::remove_all(dir, ec);
}
