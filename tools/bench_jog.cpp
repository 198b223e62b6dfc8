// bench_jog: the jog figures issue 11 asks for.
//   bench_jog [REQUESTS]
// 1. Request to bytes: a MachineSession on a pty whose other end is a small
//    GRBL stand-in on its own thread; for each step-jog request the time from
//    just before the call to the moment the `$J=` line's last byte is read on
//    the far side (same steady clock). Includes the kernel's pty hop and the
//    reader's wake-up, so it bounds what a pendant report or a key costs once
//    decoded (their decoders add microseconds: reported separately by their
//    own benches/tests).
// 2. Stop distance after a release in continuous mode at 1,000 mm/min,
//    measured in the simulated GRBL (cncsim's Machine) in virtual time, for
//    several accelerations, next to the controller's own stopping distance
//    (v^2/2a) plus one increment.
#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <boost/asio/io_context.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "cncsim/machine.hpp"
#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/protocol/grbl_session.hpp"
#include "cncstream/protocol/grbl_settings.hpp"
#include "cncstream/session/machine_session.hpp"

using namespace cncstream;
using Clock = std::chrono::steady_clock;

namespace {

// Answers like GRBL 1.1 over the pty master: banner, `$$`, `ok`, status;
// records when each `$J=` line has fully arrived.
class FakeGrbl {
 public:
  explicit FakeGrbl(int fd) : fd_(fd), thread_([this] { loop(); }) {}
  ~FakeGrbl() {
    stop_ = true;
    thread_.join();
  }
  std::vector<Clock::time_point> jog_arrivals() {
    std::lock_guard<std::mutex> l(m_);
    return arrivals_;
  }
  // Blocks (no spinning: the reader needs the CPU) until n jog lines arrived.
  bool wait_for(std::size_t n, std::chrono::milliseconds limit) {
    std::unique_lock<std::mutex> l(m_);
    return cv_.wait_for(l, limit, [&] { return arrivals_.size() >= n; });
  }

 private:
  void say(const std::string& s) { (void)!::write(fd_, s.data(), s.size()); }
  void loop() {
    std::string line;
    bool greeted = false;
    while (!stop_) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 20) <= 0) continue;
      char buf[512];
      const ssize_t n = ::read(fd_, buf, sizeof buf);
      if (n <= 0) continue;
      const auto now = Clock::now();
      if (!greeted) {
        greeted = true;
        say("\r\nGrbl 1.1h ['$' for help]\r\n");
      }
      for (ssize_t i = 0; i < n; ++i) {
        const unsigned char c = static_cast<unsigned char>(buf[i]);
        if (c == '?') {
          say("<Idle|MPos:0.000,0.000,0.000|FS:0,0|WCO:0.000,0.000,0.000>\r\n");
        } else if (c >= 0x80 || c == '!' || c == '~' || c == 0x18) {
        } else if (c == '\n') {
          if (line == "$$") say("$110=5000.000\r\n$111=5000.000\r\n$112=1000.000\r\n$120=500.000\r\n$121=500.000\r\n$122=100.000\r\n");
          if (line.rfind("$J=", 0) == 0) {
            std::lock_guard<std::mutex> l(m_);
            arrivals_.push_back(now);
            cv_.notify_all();
          }
          say("ok\r\n");
          line.clear();
        } else if (c != '\r') {
          line.push_back(static_cast<char>(c));
        }
      }
    }
  }
  int fd_;
  std::atomic<bool> stop_{false};
  std::mutex m_;
  std::condition_variable cv_;
  std::vector<Clock::time_point> arrivals_;
  std::thread thread_;
};

double percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(p * static_cast<double>(v.size())))];
}

void request_to_bytes(int requests) {
  int master = -1, slave = -1;
  char name[256];
  if (::openpty(&master, &slave, name, nullptr, nullptr) != 0) {
    std::perror("openpty");
    std::exit(1);
  }
  termios t{};
  ::tcgetattr(slave, &t);
  ::cfmakeraw(&t);
  ::tcsetattr(slave, TCSANOW, &t);
  FakeGrbl grbl(master);
  boost::asio::io_context io;
  session::MachineOptions o;
  o.name = "bench";
  o.port = std::make_shared<session::DevicePort>(name);
  o.profiles_dir = protocol::default_profiles_dir();
  session::MachineSession s(io, o);
  s.open();
  const auto deadline = Clock::now() + std::chrono::seconds(20);
  while (!(s.ready() && s.status()) && Clock::now() < deadline) io.run_for(std::chrono::milliseconds(5));
  if (!s.ready()) {
    std::fprintf(stderr, "bench_jog: the session did not become ready\n");
    std::exit(1);
  }
  std::vector<Clock::time_point> asked;
  std::vector<double> call_ms;
  for (int i = 0; i < requests; ++i) {
    // Wait until the previous jog is answered and settled (the engine queues two).
    while (s.snapshot().jogging) io.run_for(std::chrono::milliseconds(1));
    asked.push_back(Clock::now());
    const auto r = s.jog_step(protocol::JogDirection{{1, 0, 0}}, 0.01, 1000);
    call_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - asked.back()).count());
    if (!r) {
      std::fprintf(stderr, "bench_jog: refused: %s\n", r.reason.c_str());
      std::exit(1);
    }
    // The session writes in the call (asio writes a free descriptor at once):
    // nothing needs the loop until the answer comes back.
    if (!grbl.wait_for(asked.size(), std::chrono::milliseconds(300))) io.poll();
    io.run_for(std::chrono::milliseconds(2));  // the answer and a status settle it
  }
  const auto got = grbl.jog_arrivals();
  std::vector<double> ms;
  for (std::size_t i = 0; i < std::min(got.size(), asked.size()); ++i)
    ms.push_back(std::chrono::duration<double, std::milli>(got[i] - asked[i]).count());
  if (ms.size() != asked.size()) std::printf("  warning: %zu of %zu jog lines arrived\n", ms.size(), asked.size());
  std::printf("request -> bytes written (the session call, write(2) included), %zu step jogs: median %.3f ms, p99 %.3f ms, max %.3f ms\n",
              call_ms.size(), percentile(call_ms, 0.5), percentile(call_ms, 0.99), percentile(call_ms, 1.0));
  std::printf("request -> bytes read on the far side of a pty, %zu step jogs: median %.3f ms, p99 %.3f ms, max %.3f ms\n",
              ms.size(), percentile(ms, 0.5), percentile(ms, 0.99), percentile(ms, 1.0));
  ::close(slave);
}

const protocol::FirmwareProfile& grbl_profile() {
  static const auto p = protocol::load_firmware_profile(protocol::default_profiles_dir() / "grbl-1.1.toml");
  return p;
}

struct StopResult {
  double stop, increment, run_on;
};

StopResult stop_distance(double accel, double feed) {
  cncsim::Machine m;
  protocol::GrblSession host(grbl_profile());
  double t = 0;
  auto step = [&] {
    m.receive(host.take_output());
    m.advance(0.001);
    t += 0.001;
    host.on_bytes(m.take_output(), t);
    if (host.next_deadline() <= t) host.tick(t);
  };
  auto run = [&](double s) {
    const double end = t + s;
    while (t < end) step();
  };
  char line[48];
  protocol::GrblSettings table;
  for (int i = 0; i < 3; ++i) {
    std::snprintf(line, sizeof line, "$%d=%.3f", 110 + i, 5000.0);
    host.send_command(line);
    table[110 + i] = 5000;
    std::snprintf(line, sizeof line, "$%d=%.3f", 120 + i, accel);
    host.send_command(line);
    table[120 + i] = accel;
  }
  host.set_jog_limits(protocol::jog_limits_from(table));
  run(0.3);
  (void)host.jog_start(protocol::JogDirection{{1, 0, 0}}, feed, 0.3, t);
  const double stop = host.jog().stop_distance_mm(), inc = host.jog().increment_mm();
  for (int i = 0; i < 30; ++i) {
    run(0.1);
    host.jog_renew(t);
  }
  host.jog_release();
  const double at = m.machine_position().x;
  run(5);
  return {stop, inc, m.machine_position().x - at};
}

}  // namespace

int main(int argc, char** argv) {
  const int requests = argc > 1 ? std::atoi(argv[1]) : 500;
  request_to_bytes(requests);
  std::printf("\nstop distance after release, continuous jog at 1000 mm/min (cncsim, virtual time):\n");
  std::printf("  accel mm/s^2 | v^2/2a mm | increment mm | bound mm | measured run-on mm\n");
  for (double a : {10.0, 50.0, 200.0, 1000.0}) {
    const auto r = stop_distance(a, 1000);
    std::printf("  %12.0f | %9.3f | %12.3f | %8.3f | %18.3f %s\n", a, r.stop, r.increment, r.stop + r.increment,
                r.run_on, r.run_on <= r.stop + r.increment + 1e-9 ? "ok" : "OVER");
  }
  return 0;
}
