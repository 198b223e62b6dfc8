// bench_stream_sim: how full cncstream keeps GRBL's 128-byte RX buffer and
// what streaming costs it, on a long job of short lines against the
// simulator (cncsim's Machine on a pty, served from a thread) throttled so
// that it consumes about 1000 lines/s.
//   bench_stream_sim [LINES] [SIM_SPEED]
// RX fill is the host's character count (bytes sent, not yet answered) over
// the 128-byte buffer, sampled every runner tick (20 ms); CPU is
// getrusage(RUSAGE_THREAD) of the streaming thread over the job.
#include <sys/resource.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include "cncsim/machine.hpp"
#include "cncsim/pty_frontend.hpp"
#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/session/stream_runner.hpp"

namespace {
double thread_cpu_s() {
  rusage u{};
  getrusage(RUSAGE_THREAD, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}
}  // namespace

int main(int argc, char** argv) {
  const int lines = argc > 1 ? std::atoi(argv[1]) : 20000;
  // 0.2 mm moves at the sim's 500 mm/min max rate take 24 ms of machine time:
  // at speed 24 the sim consumes ~1000 lines/s.
  const double speed = argc > 2 ? std::atof(argv[2]) : 24.0;
  const auto prog = std::filesystem::temp_directory_path() / "bench_stream_sim.nc";
  {
    std::ofstream f(prog);
    f << "G21 G90 G94\nG1 Z-1 F500\n";
    for (int i = 1; i <= lines; ++i) f << "G1 X" << (i * 0.2) << " Y" << ((i % 2) * 0.001) << "\n";
    f << "M2\n";
  }
  cncsim::MachineOptions mo;
  mo.strict = true;
  cncsim::Machine machine(mo);
  cncsim::PtyFrontEnd front(machine, cncsim::PtyOptions{std::nullopt, speed});
  std::atomic<bool> stop{false};
  std::thread sim;

  cncstream::session::RunnerOptions o;
  o.port = front.slave_path();
  o.profiles_dir = cncstream::protocol::default_profiles_dir();
  o.on_port_opened = [&] { sim = std::thread([&] { front.run(stop); }); };
  double fill_sum = 0, cpu_start = 0, t_start = 0;
  long samples = 0;
  bool started = false;
  o.tick_s = 0.02;  // samples of the buffer fill
  o.on_tick = [&](const cncstream::session::MachineSnapshot& s) {
    if (!started && s.progress.lines_answered > 0) {
      started = true;
      cpu_start = thread_cpu_s();
      t_start = s.now;
    }
    if (started && s.buffer.capacity > 0 && s.progress.lines_answered + 20 < s.progress.total_lines) {
      fill_sum += double(s.buffer.in_flight) / double(s.buffer.capacity);
      ++samples;
    }
  };
  cncstream::session::StreamRunner runner(o);
  const auto r = runner.run(prog);
  const double cpu = thread_cpu_s() - cpu_start;
  const double wall = r.seconds - t_start;
  stop = true;
  if (sim.joinable()) sim.join();
  std::printf("outcome %s, %zu lines answered in %.2f s = %.0f lines/s (sim speed %.1f)\n",
              cncstream::protocol::to_string(r.outcome), r.lines_answered, wall, double(r.lines_answered) / wall, speed);
  std::printf("mean RX buffer fill %.1f %% over %ld samples; sim dropped %zu RX bytes\n",
              samples ? 100.0 * fill_sum / double(samples) : 0.0, samples, machine.rx_bytes_dropped());
  std::printf("streaming thread CPU %.3f s = %.2f %% of one core\n", cpu, 100.0 * cpu / wall);
  std::filesystem::remove(prog);
  return r.outcome == cncstream::protocol::JobOutcome::Completed ? 0 : 1;
}
