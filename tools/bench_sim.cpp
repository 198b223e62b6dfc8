// Lines per second the simulator accepts through its pty at --speed max with
// material removal on a 0.1 mm grid over 120 x 100 mm (a 1201 x 1001 stock),
// fed by a GRBL character-counting host. Short G1 lines (0.2 mm) in a raster.
//   bench_sim [--benchmark_min_time=...]
#include <benchmark/benchmark.h>

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <deque>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "cncsim/machine.hpp"
#include "cncsim/pty_frontend.hpp"
#include "cncsim/removal.hpp"

namespace {

std::vector<std::string> raster_lines(std::size_t n) {
  std::vector<std::string> lines;
  lines.reserve(n);
  char buf[64];
  double x = 1, y = 1;
  int dir = 1;
  for (std::size_t i = 0; i < n; ++i) {
    x += 0.2 * dir;
    if (x > 119 || x < 1) {
      dir = -dir;
      y += 1.0;
      if (y > 99) y = 1;
    }
    std::snprintf(buf, sizeof buf, "G1X%.3fY%.3f", x, y);
    lines.push_back(buf);
  }
  return lines;
}

class Host {
 public:
  explicit Host(const std::string& path) {
    fd_ = open(path.c_str(), O_RDWR | O_NOCTTY);
    if (fd_ < 0) throw std::runtime_error("open " + path);
    termios t{};
    tcgetattr(fd_, &t);
    cfmakeraw(&t);
    tcsetattr(fd_, TCSANOW, &t);
  }
  ~Host() { close(fd_); }
  void send_all(const std::vector<std::string>& lines) {
    std::deque<std::size_t> in_flight;
    std::size_t used = 0, next = 0;
    std::string out;
    while (next < lines.size() || !in_flight.empty()) {
      out.clear();
      while (next < lines.size() && used + lines[next].size() + 1 <= 127) {
        out += lines[next];
        out += '\n';
        used += lines[next].size() + 1;
        in_flight.push_back(lines[next].size() + 1);
        ++next;
      }
      if (!out.empty() && write(fd_, out.data(), out.size()) != static_cast<ssize_t>(out.size()))
        throw std::runtime_error("short write");
      char buf[4096];
      const ssize_t n = read(fd_, buf, sizeof buf);
      if (n <= 0) throw std::runtime_error("read failed");
      for (ssize_t i = 0; i < n; ++i) {
        if (buf[i] != '\n') continue;
        // Every line of output here is an answer (no status polling).
        if (in_flight.empty()) continue;  // the banner
        used -= in_flight.front();
        in_flight.pop_front();
      }
    }
  }

 private:
  int fd_;
};

void BM_PtyLinesWithRemoval(benchmark::State& state) {
  cncsim::MachineOptions options;
  options.instant_waits = true;
  cncsim::Machine machine(options);
  machine.take_output();  // the banner: the host does not wait for it here
  cncsim::MaterialRemoval removal({{0, 0, -5}, {120, 100, 0}, 0.1}, cncstream::cam::parse_cutter_spec("ball:3.175"));
  removal.attach(machine);
  // Start at depth so every line cuts.
  machine.receive("G0X1Y1\nG1Z-0.5F3000\n");
  machine.run_until_idle();
  machine.take_output();
  cncsim::PtyFrontEnd front(machine, {std::nullopt, 0});
  std::atomic<bool> stop{false};
  std::thread server([&] { front.run(stop); });
  const auto lines = raster_lines(static_cast<std::size_t>(state.range(0)));
  {
    Host host(front.slave_path());
    for (auto _ : state) host.send_all(lines);
  }
  stop = true;
  server.join();
  state.SetItemsProcessed(state.iterations() * state.range(0));
  state.counters["segments_cut"] = static_cast<double>(removal.segments());
}
BENCHMARK(BM_PtyLinesWithRemoval)->Arg(20000)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_InProcessLinesNoRemoval(benchmark::State& state) {
  cncsim::MachineOptions options;
  options.instant_waits = true;
  cncsim::Machine machine(options);
  machine.receive("G1F3000\n");
  const auto lines = raster_lines(static_cast<std::size_t>(state.range(0)));
  std::string all;
  for (const auto& l : lines) all += l + "\n";
  for (auto _ : state) {
    for (const auto& l : lines) {
      machine.receive(l);
      machine.receive("\n");
      benchmark::DoNotOptimize(machine.take_output());
    }
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_InProcessLinesNoRemoval)->Arg(20000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
