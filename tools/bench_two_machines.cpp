// bench_two_machines: two machine sessions driven by one thread on one
// io_context, each streaming a long job of short lines to its own simulator
// (strict 128-byte RX buffer, throttled to consume about 1000 lines/s).
//   bench_two_machines [LINES] [SIM_SPEED]
// RX fill is each session's character count (bytes sent, not yet answered)
// over the 128-byte buffer, sampled every 20 ms while more than 20 lines
// remain; CPU is getrusage(RUSAGE_THREAD) of the one thread driving both
// sessions (the simulators run on threads of their own, not counted).
#include <sys/resource.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>

#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/session/machine_session.hpp"
#include "cncstream/session/simulator_port.hpp"

using namespace cncstream::session;

namespace {

double thread_cpu_s() {
  rusage u{};
  getrusage(RUSAGE_THREAD, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

JobInput program(int lines) {
  JobInput j;
  j.file = "bench_two_machines.nc";
  j.lines = {"G21 G90 G94", "G1 Z-1 F500"};
  char buf[64];
  for (int i = 1; i <= lines; ++i) {
    std::snprintf(buf, sizeof buf, "G1 X%g Y%g", i * 0.2, (i % 2) * 0.001);
    j.lines.emplace_back(buf);
  }
  j.lines.emplace_back("M2");
  j.total_lines = static_cast<std::int64_t>(j.lines.size());
  return j;
}

struct Machine {
  std::shared_ptr<SimulatorPort> sim;
  std::unique_ptr<MachineSession> session;
  Subscription sub;
  double fill_sum = 0;
  long samples = 0;
  double started = -1, ended = -1;
  std::size_t answered = 0;
  cncstream::protocol::JobOutcome outcome{};
};

}  // namespace

int main(int argc, char** argv) {
  const int lines = argc > 1 ? std::atoi(argv[1]) : 20000;
  // 0.2 mm moves at the sim's 500 mm/min max rate take 24 ms of machine
  // time: at speed 24 each simulator consumes ~1000 lines/s.
  std::string speed = "24";
  if (argc > 2) speed = argv[2];
  boost::asio::io_context io;
  Machine m[2];
  const JobInput job = program(lines);
  int finished = 0;
  for (int k = 0; k < 2; ++k) {
    SimulatorOptions so;
    so.speed = speed;
    m[k].sim = std::make_shared<SimulatorPort>(so);
    MachineOptions mo;
    mo.name.assign(1, static_cast<char>('a' + k));
    mo.port = m[k].sim;
    mo.profiles_dir = cncstream::protocol::default_profiles_dir();
    m[k].session = std::make_unique<MachineSession>(io, mo);
    auto& mk = m[k];
    mk.sub = mk.session->subscribe([&mk, &job, &finished](const SessionEvent& e) {
      if (e.kind == SessionEventKind::Link && e.link == LinkState::Ready) {
        mk.started = e.at;
        if (auto r = mk.session->start_job(job); !r) std::fprintf(stderr, "refused: %s\n", r.reason.c_str());
      } else if (e.kind == SessionEventKind::JobEnded) {
        mk.ended = e.at;
        mk.answered = e.lines_answered;
        mk.outcome = e.outcome;
        ++finished;
      }
    });
  }
  boost::asio::steady_timer sampler(io);
  std::function<void()> sample = [&] {
    sampler.expires_after(std::chrono::milliseconds(20));
    sampler.async_wait([&](const boost::system::error_code& ec) {
      if (ec) return;
      for (auto& mk : m) {
        const auto s = mk.session->snapshot();
        if (s.job_active && s.buffer.capacity > 0 && s.progress.lines_answered + 20 < s.progress.total_lines &&
            s.progress.lines_answered > 0) {
          mk.fill_sum += double(s.buffer.in_flight) / double(s.buffer.capacity);
          ++mk.samples;
        }
      }
      if (finished < 2) sample();
      else
        for (auto& mk : m) mk.session->close();
    });
  };
  const double cpu0 = thread_cpu_s();
  for (auto& mk : m) mk.session->open();
  sample();
  io.run();
  const double cpu = thread_cpu_s() - cpu0;
  double wall = 0;
  int code = 0;
  for (auto& mk : m) {
    const double t = mk.ended - mk.started;
    wall = std::max(wall, t);
    const auto rep = mk.sim->finish(false);
    std::printf("machine %s: %s, %zu lines answered in %.2f s = %.0f lines/s, mean RX fill %.1f %% (%ld samples), "
                "sim dropped %s\n",
                mk.session->name().c_str(), cncstream::protocol::to_string(mk.outcome), mk.answered, t,
                double(mk.answered) / t, mk.samples ? 100.0 * mk.fill_sum / double(mk.samples) : 0.0, mk.samples,
                rep.overflowed ? "RX bytes (overflow)" : "nothing");
    if (mk.outcome != cncstream::protocol::JobOutcome::Completed || rep.overflowed) code = 1;
  }
  std::printf("the one thread driving both sessions: CPU %.3f s over %.2f s = %.2f %% of one core (%.2f %% per machine)\n",
              cpu, wall, 100.0 * cpu / wall, 50.0 * cpu / wall);
  return code;
}
