// The MTConnect adapter (SHDR): what an agent sees of one daemon's machine.
#include <gtest/gtest.h>

#include <poll.h>

#include "cncstream/shop/hub.hpp"
#include "cncstream/shop/schema.hpp"
#include "cncstream/shop/shdr_adapter.hpp"
#include "shop_daemon_util.hpp"
#include "shop_test_util.hpp"

using namespace cncstream;
namespace fs = std::filesystem;

namespace {

// Lines from an SHDR socket, with a deadline.
class ShdrClient {
 public:
  explicit ShdrClient(unsigned short port) : fd_(loopback::connect_to(port)) {}
  ~ShdrClient() {
    if (fd_ >= 0) ::close(fd_);
  }
  bool ok() const { return fd_ >= 0; }
  void send(const std::string& s) { loopback::send_all(fd_, s); }
  std::optional<std::string> line(double timeout_s) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (true) {
      if (const auto nl = buf_.find('\n'); nl != std::string::npos) {
        std::string l = buf_.substr(0, nl);
        buf_.erase(0, nl + 1);
        return l;
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(end - std::chrono::steady_clock::now()).count();
      if (left <= 0) return std::nullopt;
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left)) <= 0) return std::nullopt;
      char b[4096];
      const auto n = ::recv(fd_, b, sizeof b, 0);
      if (n <= 0) return std::nullopt;
      buf_.append(b, static_cast<std::size_t>(n));
    }
  }

 private:
  int fd_;
  std::string buf_;
};

// key -> value of one SHDR data line ("ts|k|v|k|v").
std::map<std::string, std::string> items(const std::string& line) {
  std::vector<std::string> f;
  std::size_t start = 0;
  while (true) {
    const auto bar = line.find('|', start);
    f.push_back(line.substr(start, bar == std::string::npos ? std::string::npos : bar - start));
    if (bar == std::string::npos) break;
    start = bar + 1;
  }
  std::map<std::string, std::string> out;
  if (f.size() > 1 && f[1] == "system") return out;  // a condition
  for (std::size_t i = 1; i + 1 < f.size(); i += 2) out[f[i]] = f[i + 1];
  return out;
}

}  // namespace

TEST(ShdrLines, AllItemsFirstThenOnlyWhatChangedAndAlarmsAsAFaultCondition) {
  shop::MachineState a;
  a.availability = "AVAILABLE";
  const std::string all = shop::shdr_lines("T", a, nullptr);
  for (const char* key : {"|avail|AVAILABLE", "|execution|READY", "|mode|MANUAL", "|program|UNAVAILABLE", "|line|0",
                          "|path_pos|UNAVAILABLE", "|path_feedrate|UNAVAILABLE", "|feed_ovr|UNAVAILABLE"})
    EXPECT_NE(all.find(key), std::string::npos) << key << " in " << all;
  EXPECT_NE(all.find("T|system|NORMAL||||\n"), std::string::npos) << all;
  shop::MachineState b = a;
  b.execution = "ACTIVE";
  b.line = 12;
  b.program = "a|b.nc";
  EXPECT_EQ(shop::shdr_lines("T", b, &a), "T|execution|ACTIVE|program|a b.nc|line|12\n");
  shop::MachineState c = b;
  c.execution = "STOPPED";
  c.alarm = "ALARM:1 Hard limit";
  EXPECT_EQ(shop::shdr_lines("T", c, &b), "T|execution|STOPPED\nT|system|FAULT|ALARM:1|||ALARM:1 Hard limit\n");
  EXPECT_EQ(shop::shdr_lines("T", c, &c), "");
}

TEST(ShopMtconnect, AnAgentSeesPongExecutionActiveThenReadyAndTheLineAdvancing) {
  SHOP_REQUIRE_POSTGRES();
  shoptest::TempPostgres pg;
  const std::string url = pg.create_database("shdr");
  shop::PgConnection admin(url);
  shop::migrate(admin);
  // Twenty 4 mm moves at 3000 mm/min, the simulator at 5 x real time (GRBL's 10 mm/s² default
  // acceleration): about 2 s.
  std::string program = "G21\nG90\nG0 X0 Y0\n";
  for (int i = 1; i <= 20; ++i) program += "G1 X" + std::to_string(4 * i) + " F3000\n";
  shop::Submission s;
  s.file_name = "steps.nc";
  s.kind = "gcode";
  s.content = program;
  shop::Hub(admin).submit_job(s);
  const fs::path dir = dtest::temp_dir("shop-shdr");
  auto m = dtest::sim_machine("mill", "5");
  auto c = shoptest::shop_daemon_config(dir / "pc", url, {m});
  c.shop.mtconnect_port = 0;
  dtest::RunningDaemon d(c);
  const auto port = d.daemon().shop()->mtconnect_port("mill");
  ASSERT_GT(port, 0);
  ASSERT_TRUE(dtest::wait_for([&] {
    return shoptest::on_loop(d.daemon(), [&] { return d.daemon().jobs().list(std::nullopt, std::string("ready"))["jobs"].size(); }) == 1;
  }, 20));
  ShdrClient agent(port);
  ASSERT_TRUE(agent.ok());
  agent.send("* PING\n");
  bool pong = false;
  std::string execution;
  std::vector<std::string> executions;
  std::vector<long> lines;
  const auto take = [&](const std::string& l) {
    if (l.starts_with("* PONG")) pong = true;
    for (const auto& [k, v] : items(l)) {
      if (k == "execution" && v != execution) executions.push_back(execution = v);
      if (k == "line") lines.push_back(std::stol(v));
    }
  };
  while (const auto l = agent.line(0.3)) take(*l);
  EXPECT_TRUE(pong) << "no * PONG to * PING";
  EXPECT_EQ(execution, "READY");
  ASSERT_EQ(shoptest::start_ready_jobs(d.daemon()), 1);
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  bool was_active = false;
  while (std::chrono::steady_clock::now() < end && !(was_active && execution == "READY")) {
    if (const auto l = agent.line(1)) take(*l);
    was_active = was_active || execution == "ACTIVE";
  }
  EXPECT_TRUE(was_active) << "executions seen: " << testing::PrintToString(executions);
  EXPECT_EQ(execution, "READY") << testing::PrintToString(executions);
  // The line advanced through the job, never back, to the program's last.
  std::vector<long> during(lines.begin(), lines.end());
  std::erase(during, 0);
  ASSERT_GE(during.size(), 3u) << testing::PrintToString(lines);
  EXPECT_TRUE(std::is_sorted(during.begin(), during.end())) << testing::PrintToString(during);
  EXPECT_EQ(during.back(), 23);
  d.shutdown();
  std::error_code ec;
  fs::remove_all(dir, ec);
}
