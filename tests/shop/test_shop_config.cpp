// The daemon's [shop] section: parsed, checked, and off without it.
#include <gtest/gtest.h>

#include "cncstream/daemon/config.hpp"

using namespace cncstream::daemon;

TEST(ShopConfig, TheShopSectionAndTheMachinesCapabilitiesAreRead) {
  const auto c = parse_config(R"(
[[machine]]
name = "router1"
port = "sim"
capabilities = ["vacuum", "ball:3.175"]
shop_claim = false

[shop]
url = "postgresql://pc@hub/shop"
name = "acme"
lease_s = 20
heartbeat_s = 2
mtconnect_port = 7878
mqtt_host = "hub"
mqtt_port = 8883
)", "d.toml");
  EXPECT_EQ(c.shop.url, "postgresql://pc@hub/shop");
  EXPECT_EQ(c.shop.name, "acme");
  EXPECT_EQ(c.shop.lease_s, 20);
  EXPECT_EQ(c.shop.heartbeat_s, 2);
  ASSERT_TRUE(c.shop.mtconnect_port);
  EXPECT_EQ(*c.shop.mtconnect_port, 7878);
  EXPECT_EQ(c.shop.mqtt_host, "hub");
  EXPECT_EQ(c.shop.mqtt_port, 8883);
  EXPECT_EQ(c.machines.at(0).capabilities, (std::vector<std::string>{"vacuum", "ball:3.175"}));
  EXPECT_FALSE(c.machines.at(0).shop_claim);
}

TEST(ShopConfig, WithoutTheSectionThereIsNoShopAndBadValuesNameTheLine) {
  EXPECT_TRUE(parse_config("listen = \"127.0.0.1:8420\"\n", "d.toml").shop.url.empty());
  EXPECT_FALSE(parse_config("listen = \"127.0.0.1:8420\"\n", "d.toml").shop.mtconnect_port);
  const auto refused = [](const std::string& text, const std::string& needle) {
    try {
      parse_config(text, "d.toml");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  refused("[shop]\nname = \"acme\"\n", "d.toml:1: shop.url");
  refused("[shop]\nurl = \"postgresql://h/s\"\nlease_s = 5\nheartbeat_s = 5\n", "heartbeat_s must be shorter");
  refused("[shop]\nurl = \"postgresql://h/s\"\nclaim = true\n", "unknown key 'shop.claim'");
}
