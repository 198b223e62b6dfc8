// bench_shop_latency: how soon a machine's state change reaches the shop
// view of another PC's web page (docs/shop.md, docs/PERFORMANCE.md).
//   bench_shop_latency [SECONDS] [DAEMONS] [MACHINES_PER_DAEMON] [MIN_READ_INTERVAL_S]   (default 60 5 8 0.2)
// A throw-away PostgreSQL on loopback (the tests' cluster, fsync off), the
// shop's schema and DAEMONS in-process daemons with simulated machines at
// real-time speed, heartbeats every 5 s as configured by default. Shop jobs
// (small programs of 2 to 6 s) keep every machine busy: claimed, started by
// an operator thread, run, and the next one claimed. Each daemon's own
// derived machine state (the shop client's, when it writes the state event
// to its outbox) is timed; a WebSocket client on every daemon times the
// `shop` frames that show another daemon's machines in that state. A change
// counts from the daemon's change to the first frame showing it or a newer
// state. CPU: PostgreSQL (the postmaster, its children and the children it
// reaped) and this process (the daemons with their simulated controllers
// and the WebSocket clients), from /proc, over the measured window.
#include <dirent.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>
#include <vector>

#include "../tests/shop/shop_daemon_util.hpp"
#include "../tests/shop/shop_test_util.hpp"
#include "cncstream/daemon/shop_watch.hpp"
#include "cncstream/shop/hub.hpp"
#include "cncstream/shop/schema.hpp"

using namespace cncstream;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

namespace {

// utime, stime, cutime, cstime of /proc/PID/stat in clock ticks; ppid too.
struct ProcTimes {
  long ppid = 0;
  double own = 0, reaped = 0;
};
bool proc_times(long pid, ProcTimes& t) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string s((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto close = s.rfind(')');
  if (close == std::string::npos) return false;
  std::istringstream f(s.substr(close + 2));
  std::vector<std::string> v;
  for (std::string x; f >> x;) v.push_back(x);
  if (v.size() < 15) return false;
  // After the name: state(0) ppid(1) ... utime(11) stime(12) cutime(13) cstime(14).
  t.ppid = std::atol(v[1].c_str());
  t.own = std::atof(v[11].c_str()) + std::atof(v[12].c_str());
  t.reaped = std::atof(v[13].c_str()) + std::atof(v[14].c_str());
  return true;
}

// CPU seconds of this process, and of PostgreSQL (our child postmaster and its children).
std::pair<double, double> cpu_now() {
  const double tick = double(::sysconf(_SC_CLK_TCK));
  ProcTimes self;
  proc_times(::getpid(), self);
  std::map<long, ProcTimes> all;
  if (DIR* d = ::opendir("/proc")) {
    while (dirent* e = ::readdir(d)) {
      const long pid = std::atol(e->d_name);
      ProcTimes t;
      if (pid > 0 && proc_times(pid, t)) all[pid] = t;
    }
    ::closedir(d);
  }
  double pg = 0;
  for (const auto& [pid, t] : all)
    if (t.ppid == ::getpid()) {  // the postmaster
      pg += t.own + t.reaped;
      for (const auto& [cpid, c] : all)
        if (c.ppid == pid) pg += c.own;
    }
  return {self.own / tick, pg / tick};
}

struct Transition {
  Clock::time_point at;
  std::string sig;
};

std::string signature(const std::string& availability, const std::string& execution, const std::string& mode,
                      const std::string& program, const std::string& alarm) {
  return availability + "|" + execution + "|" + mode + "|" + program + "|" + alarm;
}

}  // namespace

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 60;
  const int daemons = argc > 2 ? std::atoi(argv[2]) : 5;
  const int per_daemon = argc > 3 ? std::atoi(argv[3]) : 8;
  const double min_interval_s = argc > 4 ? std::atof(argv[4]) : daemon::ShopWatch::kMinIntervalS;
  if (seconds <= 0 || daemons < 2 || per_daemon < 1) {
    std::fprintf(stderr, "usage: bench_shop_latency [SECONDS] [DAEMONS>=2] [MACHINES_PER_DAEMON]\n");
    return 2;
  }
  if (!shoptest::TempPostgres::available()) {
    std::fprintf(stderr, "bench_shop_latency: PostgreSQL's initdb/postgres are not installed (scripts/setup.sh)\n");
    return 2;
  }
  spdlog::set_level(spdlog::level::warn);
  shoptest::TempPostgres pg;
  const std::string admin_url = pg.create_database("latency");
  shop::PgConnection admin(admin_url);
  shop::migrate(admin);
  admin.exec("CREATE ROLE bench_pc LOGIN IN ROLE cncstream_pc");
  const std::string pc_url = pg.url("latency", "bench_pc");
  // Enough jobs for every machine to run one after the other all along.
  {
    shop::Hub hub(admin);
    admin.exec("BEGIN");
    const int jobs = static_cast<int>(daemons * per_daemon * (seconds / 4 + 4));
    for (int i = 0; i < jobs; ++i) {
      shop::Submission s;
      s.file_name = "part" + std::to_string(i) + ".nc";
      s.kind = "gcode";
      // 10 to 30 mm there and back at 20 mm/s: 1 to 3 s of real time.
      const int x = 10 + (i * 7) % 21;
      s.content = "G21\nG90\nG1 X" + std::to_string(x) + " F1200\nG1 X0 F1200\n";
      hub.submit_job(s);
    }
    admin.exec("COMMIT");
  }

  const auto root = dtest::temp_dir("bench-shop-latency");
  std::mutex mu;
  std::map<std::string, std::vector<Transition>> changes;  // per machine, in order
  std::map<std::string, int> home;                         // machine -> its daemon
  std::vector<std::unique_ptr<dtest::RunningDaemon>> ds;
  for (int d = 0; d < daemons; ++d) {
    std::vector<daemon::MachineConfig> ms;
    for (int m = 0; m < per_daemon; ++m) {
      const std::string name = "pc" + std::to_string(d) + "-m" + std::to_string(m);
      ms.push_back(dtest::sim_machine(name, "1"));
      home[name] = d;
    }
    auto c = shoptest::shop_daemon_config(root / ("pc" + std::to_string(d)), pc_url, std::move(ms));
    c.shop.heartbeat_s = 5;
    c.shop.lease_s = 30;
    c.shop.watch_min_interval_s = min_interval_s;
    ds.push_back(std::make_unique<dtest::RunningDaemon>(c));
    auto& dd = ds.back()->daemon();
    shoptest::on_loop(dd, [&] {
      dd.shop()->client().on_state([&](const std::string& machine, const shop::MachineState& s) {
        const auto sig = signature(s.availability, s.execution, s.controller_mode, s.program, s.alarm);
        const auto now = Clock::now();
        std::lock_guard lk(mu);
        auto& v = changes[machine];
        if (v.empty() || v.back().sig != sig) v.push_back({now, sig});
      });
      return 0;
    });
  }

  // The operator: starts what waits at each machine.
  std::atomic<bool> stop{false};
  std::thread operator_thread([&] {
    while (!stop) {
      for (auto& d : ds) shoptest::start_ready_jobs(d->daemon());
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  });

  // The web pages: one client per daemon, watching the other daemons' machines.
  Clock::time_point window_start{}, window_end{};
  std::vector<double> latency_ms;
  std::atomic<long> frames{0};
  std::atomic<bool> measuring{false};
  std::vector<std::thread> clients;
  for (int d = 0; d < daemons; ++d)
    clients.emplace_back([&, d] {
      dtest::WsClient ws;
      if (ws.connect(ds[d]->port(), "/api/v1/ws?client_id=bench" + std::to_string(d)) != 101) {
        std::fprintf(stderr, "client %d: no WebSocket\n", d);
        return;
      }
      std::map<std::string, std::string> shown;
      std::map<std::string, std::size_t> cursor;
      while (!stop) {
        const auto msg = ws.recv(0.5);
        if (!msg) continue;
        const auto arrived = Clock::now();
        const json f = json::parse(*msg);
        if (f.value("type", "") != "shop") continue;
        ++frames;
        for (const auto& m : f["machines"]) {
          const std::string name = m.value("name", "");
          if (!home.count(name) || home[name] == d || !m["state"].is_object()) continue;
          const auto& st = m["state"];
          const auto sig = signature(st.value("availability", ""), st.value("execution", ""),
                                     st.value("controller_mode", ""), st.value("program", ""), st.value("alarm", ""));
          if (shown[name] == sig) continue;
          shown[name] = sig;
          std::lock_guard lk(mu);
          auto& v = changes[name];
          auto& c = cursor[name];
          // The newest change to what the frame shows: it and every change
          // before it became visible (or were overtaken) now.
          std::size_t last = v.size();
          for (std::size_t i = c; i < v.size(); ++i)
            if (v[i].sig == sig) last = i;
          if (last == v.size()) continue;
          for (std::size_t i = c; i <= last; ++i)
            if (measuring && v[i].at >= window_start)
              latency_ms.push_back(std::chrono::duration<double, std::milli>(arrived - v[i].at).count());
          c = last + 1;
        }
      }
    });

  // Warm-up: every machine registered and busy.
  std::this_thread::sleep_for(std::chrono::seconds(5));
  const auto cpu0 = cpu_now();
  window_start = Clock::now();
  measuring = true;
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  const auto cpu1 = cpu_now();
  window_end = Clock::now();
  // Changes of the window's last 2 s may still be on their way.
  std::this_thread::sleep_for(std::chrono::seconds(2));
  measuring = false;
  stop = true;
  operator_thread.join();
  for (auto& t : clients) t.join();

  std::size_t changed_in_window = 0;
  {
    std::lock_guard lk(mu);
    for (const auto& [name, v] : changes)
      for (const auto& t : v)
        if (t.at >= window_start && t.at < window_end) ++changed_in_window;
  }
  std::uint64_t reads = 0, pushed = 0;
  for (auto& d : ds) {
    reads += d->daemon().shop_watch()->reads();
    pushed += d->daemon().shop_watch()->frames_sent();
  }
  const auto completed = admin.exec("SELECT count(*) FROM shop.jobs WHERE status = 'completed'").i64(0, 0);
  const double wall = std::chrono::duration<double>(window_end - window_start).count();
  ds.clear();
  std::error_code ec;
  std::filesystem::remove_all(root, ec);

  std::sort(latency_ms.begin(), latency_ms.end());
  if (latency_ms.empty()) {
    std::fprintf(stderr, "bench_shop_latency: no change was seen\n");
    return 1;
  }
  const auto pct = [&](double p) { return latency_ms[std::min(latency_ms.size() - 1, std::size_t(p * latency_ms.size()))]; };
  std::printf("view reads at most every %.2f s per daemon\n", min_interval_s);
  std::printf("%d daemons x %d machines, real time, %.0f s: %zu state changes, %lld jobs completed in all\n", daemons,
              per_daemon, wall, changed_in_window, static_cast<long long>(completed));
  std::printf("change -> shop frame at another daemon's client: %zu samples (each change seen by %d clients): "
              "p50 %.0f ms, p95 %.0f ms, p99 %.0f ms, max %.0f ms\n",
              latency_ms.size(), daemons - 1, pct(0.5), pct(0.95), pct(0.99), latency_ms.back());
  std::printf("frames received %ld; view reads %llu, frames pushed %llu (all daemons, whole run)\n", frames.load(),
              static_cast<unsigned long long>(reads), static_cast<unsigned long long>(pushed));
  std::printf("CPU over the window, as a fraction of one core: PostgreSQL %.2f, this process (daemons, simulated "
              "controllers, clients) %.2f, together %.2f\n",
              (cpu1.second - cpu0.second) / wall, (cpu1.first - cpu0.first) / wall,
              (cpu1.first - cpu0.first + cpu1.second - cpu0.second) / wall);
  return pct(0.99) <= 500 ? 0 : 1;
}
