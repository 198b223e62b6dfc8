// bench_shop_claims: claims per second at the shop's hub (docs/shop.md).
//   bench_shop_claims [JOBS] [DAEMONS] [MACHINES_PER_DAEMON]   (default 2000 8 2)
// A throw-away PostgreSQL on loopback (the tests' cluster, fsync off as in
// the tests), the shop's schema, JOBS pending jobs; then DAEMONS threads,
// each with its own connection under the PCs' role (cncstream_pc, as a
// daemon connects), claim for their machines in turn until the queue is
// empty. Prints claims per second over the wall time from the first claim
// to the last and checks that no job was claimed twice or left behind.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <thread>
#include <vector>

#include "../tests/shop/shop_test_util.hpp"
#include "cncstream/shop/hub.hpp"
#include "cncstream/shop/schema.hpp"

using namespace cncstream::shop;

int main(int argc, char** argv) {
  const int jobs = argc > 1 ? std::atoi(argv[1]) : 2000;
  const int daemons = argc > 2 ? std::atoi(argv[2]) : 8;
  const int per_daemon = argc > 3 ? std::atoi(argv[3]) : 2;
  if (jobs < 1 || daemons < 1 || per_daemon < 1) {
    std::fprintf(stderr, "usage: bench_shop_claims [JOBS] [DAEMONS] [MACHINES_PER_DAEMON]\n");
    return 2;
  }
  if (!shoptest::TempPostgres::available()) {
    std::fprintf(stderr, "bench_shop_claims: PostgreSQL's initdb/postgres are not installed (scripts/setup.sh)\n");
    return 2;
  }
  shoptest::TempPostgres pg;
  const std::string admin_url = pg.create_database("claims");
  PgConnection admin(admin_url);
  migrate(admin);
  admin.exec("CREATE ROLE bench_pc LOGIN IN ROLE cncstream_pc");
  const std::string pc_url = pg.url("claims", "bench_pc");
  Hub admin_hub(admin);
  std::vector<std::vector<std::string>> machines(daemons);
  for (int d = 0; d < daemons; ++d)
    for (int m = 0; m < per_daemon; ++m) {
      MachineInfo info;
      info.name = "pc" + std::to_string(d) + "-m" + std::to_string(m);
      info.pc = "pc" + std::to_string(d);
      info.profile = "grbl-1.1";
      admin_hub.heartbeat(info, MachineState{}, 600);
      machines[d].push_back(info.name);
    }
  admin.exec("BEGIN");
  for (int i = 0; i < jobs; ++i) {
    Submission s;
    s.file_name = "job" + std::to_string(i) + ".nc";
    s.kind = "gcode";
    s.content = "G21\nG90\nG0 X1\n";
    admin_hub.submit_job(s);
  }
  admin.exec("COMMIT");

  using clock = std::chrono::steady_clock;
  std::mutex mu;
  std::vector<std::int64_t> claimed;
  std::vector<double> latency_ms;
  std::atomic<int> ready{0}, errors{0};
  std::atomic<bool> go{false};
  clock::time_point first = clock::time_point::max(), last{};
  std::vector<std::thread> pcs;
  for (int d = 0; d < daemons; ++d)
    pcs.emplace_back([&, d] {
      try {
        PgConnection db(pc_url);
        Hub hub(db);
        std::vector<std::int64_t> mine;
        std::vector<double> lat;
        ++ready;
        while (!go) std::this_thread::yield();
        std::vector<bool> more(machines[d].size(), true);
        clock::time_point t_first = clock::time_point::max(), t_last{};
        while (std::find(more.begin(), more.end(), true) != more.end())
          for (std::size_t m = 0; m < machines[d].size(); ++m) {
            if (!more[m]) continue;
            const auto t0 = clock::now();
            const auto j = hub.claim_job(machines[d][m], 600);
            const auto t1 = clock::now();
            if (!j) {
              more[m] = false;
              continue;
            }
            t_first = std::min(t_first, t0);
            t_last = t1;
            mine.push_back(j->id);
            lat.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
          }
        std::lock_guard lock(mu);
        claimed.insert(claimed.end(), mine.begin(), mine.end());
        latency_ms.insert(latency_ms.end(), lat.begin(), lat.end());
        first = std::min(first, t_first);
        last = std::max(last, t_last);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "daemon %d: %s\n", d, e.what());
        ++errors;
      }
    });
  while (ready + errors < daemons) std::this_thread::yield();
  go = true;
  for (auto& t : pcs) t.join();
  if (errors) return 1;

  std::map<std::int64_t, int> times;
  for (const auto id : claimed) ++times[id];
  int twice = 0;
  for (const auto& [id, n] : times) twice += n > 1;
  const double wall_s = std::chrono::duration<double>(last - first).count();
  std::sort(latency_ms.begin(), latency_ms.end());
  const auto pct = [&](double p) { return latency_ms[std::min(latency_ms.size() - 1, std::size_t(p * latency_ms.size()))]; };
  std::printf("jobs %d, daemons %d x %d machines: %zu claims in %.3f s = %.0f claims/s; claim p50 %.2f ms, p99 %.2f ms\n",
              jobs, daemons, per_daemon, claimed.size(), wall_s, double(claimed.size()) / wall_s, pct(0.5), pct(0.99));
  std::printf("claimed twice: %d; left pending: %lld\n", twice,
              static_cast<long long>(admin.exec("SELECT count(*) FROM shop.jobs WHERE status = 'pending'").i64(0, 0)));
  return twice == 0 && int(times.size()) == jobs ? 0 : 1;
}
