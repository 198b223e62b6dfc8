#pragma once
// Daemons in a shop for the tests: in-process daemons (tests/daemon's
// RunningDaemon) whose config names the hub, and an operator who starts
// the jobs that wait at the machines.
#include <boost/asio/post.hpp>

#include <signal.h>
#include <sys/wait.h>

#include <future>

#include "../daemon/daemon_test_util.hpp"
#include "cncstream/daemon/job_manager.hpp"
#include "cncstream/daemon/machines.hpp"
#include "cncstream/daemon/shop_link.hpp"

namespace shoptest {

namespace fs = std::filesystem;

// Runs `f` on the daemon's event loop and returns its result.
template <typename F>
auto on_loop(cncstream::daemon::Daemon& d, F f) -> decltype(f()) {
  std::promise<decltype(f())> p;
  boost::asio::post(d.io(), [&] {
    try {
      p.set_value(f());
    } catch (...) {
      p.set_exception(std::current_exception());
    }
  });
  return p.get_future().get();
}

inline cncstream::daemon::DaemonConfig shop_daemon_config(const fs::path& dir, const std::string& url,
                                                          std::vector<cncstream::daemon::MachineConfig> machines) {
  auto c = dtest::test_config(dir);
  c.machines = std::move(machines);
  c.limits.worker_threads = 1;
  c.shop.url = url;
  c.shop.pc = dir.filename().string().substr(0, 40);
  c.shop.lease_s = 10;
  c.shop.heartbeat_s = 0.5;
  return c;
}

// The operator at each machine: starts the jobs that are ready on machines
// that run nothing; returns how many it started.
inline int start_ready_jobs(cncstream::daemon::Daemon& d) {
  return on_loop(d, [&] {
    int n = 0;
    const auto list = d.jobs().list(std::nullopt, std::string("ready"));
    for (const auto& j : list["jobs"]) {
      auto* m = d.machines().find(j["machine"].get<std::string>());
      if (!m || m->session->job_active() || !m->session->ready()) continue;
      d.machines().set_control(*m, "operator");
      try {
        d.jobs().start(j["id"].get<std::int64_t>(), "operator");
        ++n;
      } catch (const cncstream::daemon::ApiError&) {
      }
    }
    return n;
  });
}

// A daemon in a child process (forked while the test has no thread), killed
// by the test with SIGKILL as a PC that dies; reaped in any case.
struct DaemonChild {
  pid_t pid = -1;
  void kill9() {
    if (pid <= 0) return;
    ::kill(pid, SIGKILL);
    ::waitpid(pid, nullptr, 0);
    pid = -1;
  }
  ~DaemonChild() { kill9(); }
};

inline std::string tiny_program(int i) {
  return "G21\nG90\nG0 X" + std::to_string(1 + i % 7) + "\nG1 X0 F3000\n";
}

}  // namespace shoptest
