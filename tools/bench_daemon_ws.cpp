// cncstreamd under load (figures in docs/PERFORMANCE.md):
//  1. 50 WebSocket clients watch a job streaming to `sim` at full speed:
//     status latency (daemon receipt of the controller's report -> client
//     receipt; one host, one clock), lines lost, and the event loop's CPU
//     time beyond the same job with no client.
//  2. The plaque's tool path over the API: POST /jobs -> ready, then the same
//     parameters again (the cache).
//  3. Status latency while a 600k-facet part is computed on the workers.
// Usage: bench_daemon_ws [clients=50] [program lines=60000] [sim speed=10]
#include <pthread.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <thread>
#include <vector>

#include "../tests/daemon/daemon_test_util.hpp"
#include "cncstream/geometry/stl.hpp"

using namespace dtest;

namespace {

double cpu_seconds(clockid_t c) {
  timespec t{};
  clock_gettime(c, &t);
  return double(t.tv_sec) + double(t.tv_nsec) * 1e-9;
}

std::int64_t now_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

struct Watchers {
  std::vector<std::unique_ptr<WsClient>> clients;
  std::vector<std::thread> threads;
  std::mutex mu;
  std::vector<double> latency_ms;
  std::atomic<bool> stop{false};
  std::atomic<long> frames{0};

  void start(unsigned short port, int n, const std::string& machine) {
    for (int i = 0; i < n; ++i) {
      auto c = std::make_unique<WsClient>();
      if (c->connect(port, "/api/v1/ws?client_id=w" + std::to_string(i)) != 101) {
        std::fprintf(stderr, "client %d: upgrade failed\n", i);
        continue;
      }
      c->send(json{{"type", "subscribe"}, {"machines", {machine}}});
      clients.push_back(std::move(c));
    }
    for (auto& c : clients)
      threads.emplace_back([this, cl = c.get()] {
        std::vector<double> mine;
        while (!stop) {
          const auto m = cl->recv(0.2);
          if (!m) {
            if (cl->closed()) break;
            continue;
          }
          ++frames;
          if (m->find("\"type\":\"status\"") == std::string::npos) continue;
          const auto j = json::parse(*m);
          if (j.contains("reported_us")) mine.push_back(double(now_us() - j["reported_us"].get<std::int64_t>()) / 1000.0);
        }
        std::lock_guard l(mu);
        latency_ms.insert(latency_ms.end(), mine.begin(), mine.end());
      });
  }
  void finish() {
    stop = true;
    for (auto& t : threads) t.join();
    threads.clear();
    clients.clear();
  }
  void clear() {
    std::lock_guard l(mu);
    latency_ms.clear();
  }
  std::string summary() {
    std::lock_guard l(mu);
    if (latency_ms.empty()) return "no status frames";
    auto v = latency_ms;
    std::sort(v.begin(), v.end());
    auto pct = [&](double p) { return v[std::min(v.size() - 1, std::size_t(p * double(v.size())))]; };
    char b[200];
    std::snprintf(b, sizeof b, "%zu status frames, latency p50 %.2f ms, p99 %.2f ms, max %.2f ms", v.size(), pct(0.5),
                  pct(0.99), v.back());
    return b;
  }
};

std::string program(int n) {
  std::string g = "G21\nG90\nG0 Z1\nG1 F3000\n";
  for (int i = 0; i < n; ++i) {
    char b[64];
    std::snprintf(b, sizeof b, "G1 X%.3f Y%.3f\n", 10 + 5 * std::sin(i * 0.01), 10 + 5 * std::cos(i * 0.013));
    g += b;
  }
  return g;
}

struct RunFigures {
  double wall = 0, loop_cpu = 0;
  long answered = 0, total = 0;
  std::string state;
};

// A height field of n x n cells, two facets each: 2 n^2 facets.
void write_big_mesh(const fs::path& p, int n) {
  cncstream::geometry::Mesh m;
  const double s = 100.0 / n;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x)
      m.vertices.push_back({x * s, y * s, 5 + 2 * std::sin(x * 0.05) * std::cos(y * 0.07)});
  auto v = [&](int x, int y) { return static_cast<std::uint32_t>(y * (n + 1) + x); };
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      m.triangles.push_back({v(x, y), v(x + 1, y), v(x + 1, y + 1)});
      m.triangles.push_back({v(x, y), v(x + 1, y + 1), v(x, y + 1)});
    }
  cncstream::geometry::write_stl_binary(p, m);
}

}  // namespace

int main(int argc, char** argv) {
  const int clients = argc > 1 ? std::atoi(argv[1]) : 50;
  const int lines = argc > 2 ? std::atoi(argv[2]) : 60000;
  const std::string speed = argc > 3 ? argv[3] : "10";
  const auto dir = temp_dir("bench");
  auto cfg = test_config(dir);
  cfg.machines = {sim_machine("sim", speed)};
  cfg.machines[0].sim_verify = false;
  cfg.limits.max_ws_clients = 256;
  cfg.limits.max_connections = 512;
  cncstream::daemon::Daemon daemon(cfg);
  clockid_t loop_clock{};
  std::atomic<bool> have_clock{false};
  std::thread loop([&] {
    pthread_getcpuclockid(pthread_self(), &loop_clock);
    have_clock = true;
    daemon.run();
  });
  while (!have_clock) std::this_thread::yield();
  Http h;
  h.port = daemon.port();
  h.headers["X-Client-Id"] = "bench";
  wait_for([&] { return h.get("/api/v1/machines/sim").j()["link"] == "ready"; }, 30);

  const std::string text = program(lines);
  const auto up = h.request("POST", "/api/v1/files?name=bench.nc", text, {{"Content-Type", "text/plain"}});
  const json file = up.j();

  auto run = [&](const char* label) {
    Http hh = h;
    const auto id = hh.post("/api/v1/jobs", {{"machine", "sim"}, {"file", file["id"]}}).j()["id"].get<std::int64_t>();
    hh.post("/api/v1/machines/sim/control");
    const std::string base = "/api/v1/jobs/" + std::to_string(id);
    wait_for([&] { return hh.get(base).j()["state"] == "ready"; }, 60);
    const double c0 = cpu_seconds(loop_clock);
    const auto t0 = std::chrono::steady_clock::now();
    hh.post(base + "/start");
    json j;
    wait_for([&] {
      j = hh.get(base).j();
      const auto s = j["state"].get<std::string>();
      return s != "running" && s != "ready";
    }, 600);
    RunFigures f;
    f.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    f.loop_cpu = cpu_seconds(loop_clock) - c0;
    f.answered = j["progress"]["lines_answered"].get<long>();
    f.total = j["program"]["lines"].get<long>();
    f.state = j["state"];
    std::printf("%s: %s, %ld/%ld lines answered in %.2f s (%.0f lines/s), event loop CPU %.2f s (%.1f %% of a core)\n",
                label, f.state.c_str(), f.answered, f.total, f.wall, double(f.answered) / f.wall, f.loop_cpu,
                100 * f.loop_cpu / f.wall);
    return f;
  };

  const RunFigures alone = run("no client");
  Watchers w;
  w.start(daemon.port(), clients, "sim");
  std::printf("%zu WebSocket clients connected\n", w.clients.size());
  const RunFigures watched = run("watched");
  w.finish();
  std::printf("watched by %d clients: %s; %ld frames\n", clients, w.summary().c_str(), w.frames.load());
  std::printf("event loop CPU for the watchers: %.1f %% of a core beyond streaming (%.2f s vs %.2f s over %.2f s)\n",
              100 * (watched.loop_cpu - alone.loop_cpu * watched.wall / alone.wall) / watched.wall, watched.loop_cpu,
              alone.loop_cpu, watched.wall);

  // 2. The plaque's tool path over the API, then the cache.
  const auto plaque = read_file(std::string(CNCSTREAM_SOURCE_DIR) + "/examples/plaque.stl");
  const auto pf = h.request("POST", "/api/v1/files?name=plaque.stl", plaque, {{"Content-Type", "application/octet-stream"}}).j();
  const json params = {{"tool", "ball:3.175"}, {"stepover", 0.4}};
  auto t0 = std::chrono::steady_clock::now();
  const auto id = h.post("/api/v1/jobs", {{"machine", "sim"}, {"file", pf["id"]}, {"params", params}}).j()["id"].get<std::int64_t>();
  wait_for([&] { return h.get("/api/v1/jobs/" + std::to_string(id)).j()["state"] == "ready"; }, 120);
  const double first = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  t0 = std::chrono::steady_clock::now();
  const auto again = h.post("/api/v1/jobs", {{"machine", "sim"}, {"file", pf["id"]}, {"params", params}}).j();
  const double second = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::printf("plaque tool path (ball:3.175, stepover 0.4) over the API: ready in %.2f s (%s lines); same parameters again: %s in %.1f ms (cached: %s)\n",
              first, h.get("/api/v1/jobs/" + std::to_string(id)).j()["program"]["lines"].dump().c_str(),
              again["state"].get<std::string>().c_str(), second, again["generation"]["cached"].dump().c_str());

  // 3. Status latency while a 600k-facet part is computed.
  const fs::path big = dir / "big.stl";
  write_big_mesh(big, 550);
  const auto bf = h.request("POST", "/api/v1/files?name=big.stl", read_file(big), {{"Content-Type", "application/octet-stream"}}, 120).j();
  std::printf("big part: %s facets\n", bf["facets"].dump().c_str());
  Watchers w2;
  w2.stop = false;
  w2.start(daemon.port(), clients, "sim");
  const auto bid = h.post("/api/v1/jobs", {{"machine", "sim"}, {"file", bf["id"]}, {"params", {{"tool", "ball:1"}, {"stepover", 0.1}}}}).j();
  t0 = std::chrono::steady_clock::now();
  const auto bidn = bid["id"].get<std::int64_t>();
  // A job streams meanwhile, so status comes at the streaming cadence.
  std::thread streamer([&] { run("streaming while the big part is computed"); });
  wait_for([&] {
    const auto s = h.get("/api/v1/jobs/" + std::to_string(bidn)).j()["state"];
    return s != "generating" && s != "queued";
  }, 600);
  const double gen = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  streamer.join();
  w2.finish();
  std::printf("600k-facet tool path computed in %.1f s (%s); status meanwhile (%d clients): %s\n", gen,
              h.get("/api/v1/jobs/" + std::to_string(bidn)).j()["state"].get<std::string>().c_str(), clients,
              w2.summary().c_str());
  daemon.stop();
  loop.join();
  fs::remove_all(dir);
  return 0;
}
