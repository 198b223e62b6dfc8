// The daemon's pure parts: per-client coalescing, the token comparison, file
// labels, static paths, URL decoding, configuration errors, parameter checks.
#include <gtest/gtest.h>

#include <fstream>

#include "cncstream/daemon/api.hpp"
#include "cncstream/daemon/auth.hpp"
#include "cncstream/daemon/config.hpp"
#include "cncstream/daemon/file_store.hpp"
#include "cncstream/daemon/http_types.hpp"
#include "cncstream/daemon/job_params.hpp"
#include "cncstream/daemon/router.hpp"
#include "cncstream/daemon/ws_hub.hpp"
#include "daemon_test_util.hpp"

using namespace cncstream::daemon;
using nlohmann::json;

TEST(ClientQueue, KeepsOnlyTheLatestStatusPerMachineAndOrdersTheRest) {
  ClientQueue q(3);
  q.push_status("a", WsHub::frame("a1"));
  q.push_status("b", WsHub::frame("b1"));
  q.push_status("a", WsHub::frame("a2"));
  EXPECT_TRUE(q.push(WsHub::frame("m1")));
  EXPECT_TRUE(q.push(WsHub::frame("m2")));
  EXPECT_EQ(q.statuses_replaced(), 1u);
  EXPECT_EQ(*q.pop(), "a2");  // statuses first, a's latest only
  EXPECT_EQ(*q.pop(), "b1");
  EXPECT_EQ(*q.pop(), "m1");
  EXPECT_EQ(*q.pop(), "m2");
  EXPECT_EQ(q.pop(), nullptr);
}

TEST(ClientQueue, RefusesBeyondItsBound) {
  ClientQueue q(2);
  EXPECT_TRUE(q.push(WsHub::frame("1")));
  EXPECT_TRUE(q.push(WsHub::frame("2")));
  EXPECT_FALSE(q.push(WsHub::frame("3")));
  for (int i = 0; i < 1000; ++i) q.push_status("m", WsHub::frame(std::to_string(i)));  // never grows
  EXPECT_EQ(q.size(), 3u);
}

namespace {
struct FakePeer : WsPeer {
  int kicks = 0;
  std::string closed;
  void kick() override { ++kicks; }
  void close_slow(const std::string& why) override { closed = why; }
};
}  // namespace

TEST(WsHub, DropsASlowClientWithoutTouchingTheOthers) {
  WsHub hub(4, 3);
  auto slow = std::make_shared<FakePeer>(), fast = std::make_shared<FakePeer>();
  auto a = hub.add("slow", slow);
  auto b = hub.add("fast", fast);
  a->all_machines = b->all_machines = true;
  for (int i = 0; i < 4; ++i) {
    hub.publish("m", WsHub::frame("x"));
    while (b->queue.pop()) {  // the fast one drains as it goes
    }
  }
  EXPECT_FALSE(slow->closed.empty());
  EXPECT_TRUE(fast->closed.empty());
  EXPECT_EQ(fast->kicks, 4);
}

TEST(WsHub, CapsClients) {
  WsHub hub(2, 8);
  auto p = std::make_shared<FakePeer>();
  EXPECT_TRUE(hub.add("a", p));
  EXPECT_TRUE(hub.add("b", p));
  EXPECT_EQ(hub.add("c", p), nullptr);
}

TEST(Auth, ConstantTimeEqual) {
  EXPECT_TRUE(constant_time_equal("abc", "abc"));
  EXPECT_FALSE(constant_time_equal("abc", "abd"));
  EXPECT_FALSE(constant_time_equal("abc", "ab"));
  EXPECT_FALSE(constant_time_equal("abc", "abcd"));
  EXPECT_FALSE(constant_time_equal("abc", ""));
  EXPECT_EQ(random_token_hex().size(), 64u);
  EXPECT_NE(random_token_hex(), random_token_hex());
}

TEST(Auth, TokenFileIsCreatedPrivateAndRefusedWhenOpenToOthers) {
  const auto dir = dtest::temp_dir("token");
  bool created = false;
  const auto t = load_or_create_token(dir, created);
  EXPECT_TRUE(created);
  EXPECT_EQ(std::filesystem::status(dir / "token").permissions() & std::filesystem::perms::all,
            std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
  EXPECT_EQ(load_or_create_token(dir, created), t);
  EXPECT_FALSE(created);
  std::filesystem::permissions(dir / "token", std::filesystem::perms::group_read, std::filesystem::perm_options::add);
  EXPECT_THROW(load_or_create_token(dir, created), std::runtime_error);
  std::filesystem::remove_all(dir);
}

TEST(FileStore, LabelsNeverBecomePaths) {
  EXPECT_EQ(sanitize_label("../../etc/passwd"), ".._.._etc_passwd");
  EXPECT_EQ(sanitize_label("a\\b\nc"), "a_b_c");
  EXPECT_EQ(sanitize_label(".."), "unnamed");
  EXPECT_EQ(sanitize_label(""), "unnamed");
  EXPECT_EQ(sanitize_label(std::string(1000, 'x')).size(), 255u);
  EXPECT_TRUE(is_file_id(std::string(64, 'a')));
  EXPECT_FALSE(is_file_id(std::string(64, 'A')));
  EXPECT_FALSE(is_file_id("../" + std::string(61, 'a')));
}

TEST(StaticFiles, NothingOutsideTheRoot) {
  const auto dir = dtest::temp_dir("static");
  std::filesystem::create_directories(dir / "web" / "js");
  std::ofstream(dir / "web" / "js" / "app.js") << "x";
  std::ofstream(dir / "secret.txt") << "secret";
  std::filesystem::create_symlink(dir / "secret.txt", dir / "web" / "link.txt");
  const auto root = dir / "web";
  EXPECT_TRUE(safe_static_path(root, "js/app.js"));
  EXPECT_FALSE(safe_static_path(root, "../secret.txt"));
  EXPECT_FALSE(safe_static_path(root, "js/../../secret.txt"));
  EXPECT_FALSE(safe_static_path(root, "/etc/passwd"));
  EXPECT_FALSE(safe_static_path(root, "js\\..\\..\\secret.txt"));
  EXPECT_FALSE(safe_static_path(root, "link.txt"));  // a symlink out of the root
  EXPECT_FALSE(safe_static_path(root, ".hidden"));
  EXPECT_FALSE(safe_static_path(root, "js"));  // a folder is no file
  EXPECT_EQ(content_type_for("a.js"), "text/javascript; charset=utf-8");
  EXPECT_EQ(content_type_for("a.css"), "text/css; charset=utf-8");
  EXPECT_EQ(content_type_for("index.html"), "text/html; charset=utf-8");
  std::filesystem::remove_all(dir);
}

TEST(Router, DecodesTargetsAndRefusesBadEscapes) {
  std::string path;
  std::map<std::string, std::string> q;
  ASSERT_TRUE(split_target("/api/v1/files?name=a%20b+c.stl&x", path, q));
  EXPECT_EQ(path, "/api/v1/files");
  EXPECT_EQ(q["name"], "a b c.stl");
  EXPECT_FALSE(split_target("/static/%00x", path, q));
  EXPECT_FALSE(split_target("/static/%zz", path, q));
  EXPECT_FALSE(split_target("/static/%2", path, q));
  EXPECT_FALSE(split_target("relative", path, q));
  Router r;
  r.add("GET", "/api/v1/jobs/{id}", [](Request&, Respond) {});
  r.add("GET", "/static/*", [](Request&, Respond) {});
  Request req;
  req.method = "GET";
  req.path = "/api/v1/jobs/42";
  int status = 0;
  ASSERT_TRUE(r.match(req, status));
  EXPECT_EQ(req.params.at(0), "42");
  req.method = "POST";
  EXPECT_FALSE(r.match(req, status));
  EXPECT_EQ(status, 405);
  req.method = "GET";
  req.path = "/static/js/app.js";
  ASSERT_TRUE(r.match(req, status));
  EXPECT_EQ(req.params.at(0), "js/app.js");
  req.path = "/nothing";
  EXPECT_FALSE(r.match(req, status));
  EXPECT_EQ(status, 404);
}

TEST(Config, DefaultsWithoutAFile) {
  DaemonConfig c;
  EXPECT_EQ(c.listen_address, "127.0.0.1");
  EXPECT_EQ(c.listen_port, 8420);
  ASSERT_EQ(c.machines.size(), 1u);
  EXPECT_EQ(c.machines[0].port, "sim");
  EXPECT_FALSE(c.token_required());
  apply_listen(c, "0.0.0.0:9000");
  EXPECT_TRUE(c.token_required());
  apply_listen(c, "[::1]:9000");
  EXPECT_FALSE(c.token_required());
}

TEST(Config, ParsesMachinesAndNamesTheLineOfABadValue) {
  const auto c = parse_config(R"(listen = "127.0.0.1:9100"
[[machine]]
name = "router"
port = "/dev/serial/by-id/usb-x"
baud = 115200
[[machine]]
name = "s"
port = "sim"
sim_speed = "max"
[limits]
max_upload_bytes = 1000
)", "cncstreamd.toml");
  EXPECT_EQ(c.listen_port, 9100);
  ASSERT_EQ(c.machines.size(), 2u);
  EXPECT_EQ(c.machines[0].port, "/dev/serial/by-id/usb-x");
  EXPECT_EQ(c.limits.max_upload_bytes, 1000u);
  try {
    parse_config("listen = \"127.0.0.1:1\"\n[limits]\nmax_ws_clients = \"many\"\n", "bad.toml");
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("bad.toml:3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("max_ws_clients"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_config("[[machine]]\nname = \"a\"\n[[machine]]\nname = \"a\"\n", "dup.toml"), std::invalid_argument);
  EXPECT_THROW(parse_config("colour = 3\n", "unknown.toml"), std::invalid_argument);
  EXPECT_THROW(parse_config("listen = [\n", "syntax.toml"), std::invalid_argument);
  const auto m = parse_machine_option("shop=/dev/ttyUSB0,profile=grbl-1.1,baud=250000");
  EXPECT_EQ(m.name, "shop");
  EXPECT_EQ(m.port, "/dev/ttyUSB0");
  EXPECT_EQ(m.profile, "grbl-1.1");
  EXPECT_EQ(m.baud, 250000u);
  EXPECT_THROW(parse_machine_option("noport"), std::invalid_argument);
}

TEST(JobParams, AbsurdValuesAreRefusedNamingTheField) {
  FileInfo f;
  f.kind = "stl";
  f.bbox = {0, 0, 0, 120, 100, 10};
  Limits l;
  auto err = [&](const json& p) -> std::string {
    try {
      check_toolpath_params(p, f, l);
    } catch (const ApiError& e) {
      EXPECT_EQ(e.status, 400);
      return e.message;
    }
    return "";
  };
  EXPECT_NE(err({{"tool", "ball:3.175"}, {"stepover", -1}}).find("stepover"), std::string::npos);
  EXPECT_NE(err({{"tool", "ball:3.175"}, {"stepover", "wide"}}).find("stepover"), std::string::npos);
  EXPECT_NE(err({{"stepover", 1}}).find("tool"), std::string::npos);
  EXPECT_NE(err({{"tool", "spoon:3"}}).find("tool"), std::string::npos);
  EXPECT_NE(err({{"tool", "ball:3.175"}, {"direction", "z"}}).find("direction"), std::string::npos);
  EXPECT_NE(err({{"tool", "ball:3.175"}, {"feed", 0}}).find("feed"), std::string::npos);
  EXPECT_NE(err({{"tool", "ball:3.175"}, {"bounds", {1, 2, 0, 3}}}).find("bounds"), std::string::npos);
  // 10^12 nodes: a 200 m square sampled every 0.005 mm with 0.01 mm rows.
  EXPECT_NE(err({{"tool", "ball:3.175"}, {"stepover", 0.01}, {"step", 0.005}, {"bounds", {-1e5, -1e5, 1e5, 1e5}}})
                .find("would sample"),
            std::string::npos);
  EXPECT_NE(err({{"tool", "ball:3.175"}, {"rest", "spoon:1"}}).find("rest"), std::string::npos);
  EXPECT_NE(err({{"tool", "ball:3.175"}, {"rest", 1}}).find("rest"), std::string::npos);
  const auto ok = check_toolpath_params({{"tool", "ball:3.175"}, {"stepover", 2}}, f, l);
  EXPECT_EQ(ok.canonical["stepover"], 2.0);
  EXPECT_EQ(ok.canonical["origin"], "min");
  EXPECT_TRUE(ok.canonical["rest"].is_null());
  EXPECT_LT(ok.grid_nodes, 1e6);
  // A rest cutter is part of what the cache tells apart.
  const auto rest = check_toolpath_params({{"tool", "ball:3.175"}, {"stepover", 2}, {"rest", "ball:1/32in"}}, f, l);
  ASSERT_TRUE(rest.params.rest);
  EXPECT_EQ(rest.canonical["rest"], rest.params.rest->spec());
  EXPECT_NE(rest.canonical.dump(), ok.canonical.dump());
}

TEST(Config, PendantsNameTheMachineTheyDrive) {
  const auto c = parse_config(R"([[machine]]
name = "router"
port = "sim"
[[pendant]]
machine = "router"
lease_s = 0.25
macros = ["2=G0 Z10", "5=@unlock"]
)",
                              "pendant.toml");
  ASSERT_EQ(c.pendants.size(), 1u);
  EXPECT_EQ(c.pendants[0].machine, "router");
  EXPECT_DOUBLE_EQ(c.pendants[0].lease_s, 0.25);
  EXPECT_EQ(c.pendants[0].macros.size(), 2u);
  try {
    parse_config("[[machine]]\nname = \"router\"\n[[pendant]]\nmachine = \"mill\"\n", "wrong.toml");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no machine named 'mill' (configured: router)"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_config("[[pendant]]\nlease_s = 0.2\n", "nomachine.toml"), std::invalid_argument);
  EXPECT_THROW(parse_config("[[machine]]\nname = \"a\"\n[[pendant]]\nmachine = \"a\"\nlease_s = 9\n", "lease.toml"),
               std::invalid_argument);
}
