// Live telemetry over MQTT against a throw-away Mosquitto on loopback.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cncstream/shop/hub.hpp"
#include "cncstream/shop/mqtt.hpp"
#include "cncstream/shop/schema.hpp"
#include "mosquitto_test_util.hpp"
#include "shop_daemon_util.hpp"

using namespace cncstream;
namespace fs = std::filesystem;
using nlohmann::json;

// A daemon that vanishes (kill -9: no DISCONNECT) is marked UNAVAILABLE by
// its client's last will, retained for whoever subscribes later.
TEST(ShopMqtt, TheLastWillMarksAVanishedDaemonsMachineUnavailable) {
  SHOP_REQUIRE_MOSQUITTO();
  shoptest::TempMosquitto broker;
  const fs::path dir = dtest::temp_dir("mqtt-will");
  // The daemon's side in a child process (forked before this process has threads).
  const pid_t child = ::fork();
  if (child == 0) {
    try {
      shop::Outbox outbox(dir / "journal.sqlite");
      shop::MqttSettings s;
      s.port = broker.port();
      s.shop = "acme";
      s.keepalive_s = 5;  // libmosquitto's least
      shop::MqttMachine m(s, "router1", outbox);
      ::sleep(60);
    } catch (...) {
      ::_exit(1);
    }
    ::_exit(0);
  }
  shoptest::Subscriber sub(broker.port(), "cncstream/acme/#");
  const std::string topic = "cncstream/acme/router1/availability";
  EXPECT_TRUE(dtest::wait_for([&] { return sub.last(topic) == "AVAILABLE"; }, 10));
  ::kill(child, SIGKILL);
  ::waitpid(child, nullptr, 0);
  EXPECT_TRUE(dtest::wait_for([&] { return sub.last(topic) == "UNAVAILABLE"; }, 15)) << "the last will did not fire";
  shoptest::Subscriber later(broker.port(), "cncstream/acme/+/availability");
  EXPECT_TRUE(dtest::wait_for([&] { return later.last(topic) == "UNAVAILABLE"; }, 5)) << "the will was not retained";
  std::error_code ec;
  fs::remove_all(dir, ec);
}

// A daemon in a shop publishes its machine's retained state and its events
// at QoS 1 in order; after a broker restart (which forgets retained
// messages) the state and the availability come back.
TEST(ShopMqtt, StateAndEventsArriveAndABrokerRestartBringsTheRetainedStateBack) {
  SHOP_REQUIRE_POSTGRES();
  SHOP_REQUIRE_MOSQUITTO();
  shoptest::TempPostgres pg;
  shoptest::TempMosquitto broker;
  const std::string url = pg.create_database("mqtt");
  shop::PgConnection admin(url);
  shop::migrate(admin);
  shop::Submission job;
  job.file_name = "part.nc";
  job.kind = "gcode";
  job.content = shoptest::tiny_program(3);
  shop::Hub(admin).submit_job(job);
  const fs::path dir = dtest::temp_dir("shop-mqtt");
  auto c = shoptest::shop_daemon_config(dir / "pc", url, {dtest::sim_machine("router1")});
  c.shop.name = "acme";
  c.shop.mqtt_host = "127.0.0.1";
  c.shop.mqtt_port = broker.port();
  c.shop.mqtt_keepalive_s = 5;
  dtest::RunningDaemon d(c);
  shoptest::Subscriber sub(broker.port(), "cncstream/acme/#");
  const std::string base = "cncstream/acme/router1/";
  ASSERT_TRUE(dtest::wait_for([&] { return sub.last(base + "availability") == "AVAILABLE"; }, 10));
  ASSERT_TRUE(dtest::wait_for([&] {
    const auto s = sub.last(base + "state");
    return s && json::parse(*s).value("availability", "") == "AVAILABLE";
  }, 10));
  // The operator runs the claimed job; its events arrive in order.
  ASSERT_TRUE(dtest::wait_for([&] { return shoptest::start_ready_jobs(d.daemon()) == 1; }, 20));
  const auto done = [&] {
    for (const auto& p : sub.payloads(base + "events")) {
      const auto e = json::parse(p);
      if (e["kind"] == "job" && e["body"]["state"] == "done") return true;
    }
    return false;
  };
  ASSERT_TRUE(dtest::wait_for(done, 20));
  std::int64_t prev = 0;
  for (const auto& p : sub.payloads(base + "events")) {
    const auto seq = json::parse(p)["seq"].get<std::int64_t>();
    if (prev) {
      EXPECT_EQ(seq, prev + 1) << "events out of order or missing";
    }
    prev = seq;
  }
  // The broker restarts and forgets everything retained.
  broker.stop();
  ASSERT_TRUE(dtest::wait_for([&] { return !d.daemon().shop()->client().mqtt_connected("router1"); }, 10));
  broker.start();
  ASSERT_TRUE(dtest::wait_for([&] { return d.daemon().shop()->client().mqtt_connected("router1"); }, 15));
  shoptest::Subscriber after(broker.port(), "cncstream/acme/#");
  EXPECT_TRUE(dtest::wait_for([&] { return after.last(base + "availability") == "AVAILABLE"; }, 10));
  EXPECT_TRUE(dtest::wait_for([&] {
    const auto s = after.last(base + "state");
    return s && json::parse(*s).value("execution", "") == "READY";
  }, 10)) << "the retained state did not come back after the broker's restart";
  d.shutdown();
  std::error_code ec;
  fs::remove_all(dir, ec);
}
