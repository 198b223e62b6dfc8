// MachineSession against the in-process simulator: several machines on one
// thread, jogs between jobs, refusals, and a port that vanishes and returns.
#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <thread>

#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/session/job_journal.hpp"
#include "cncstream/session/machine_session.hpp"
#include "support/run_until.hpp"
#include "cncstream/session/simulator_port.hpp"

using namespace cncstream::session;
using cncstream::protocol::EventKind;
using cncstream::protocol::JobOutcome;
using cncstream::protocol::JogDirection;
using cncstream::protocol::MachineState;
namespace fs = std::filesystem;
using cncstream::test::run_until;

namespace {

fs::path temp_dir() {
  const auto d = fs::temp_directory_path() / ("cncstream_session_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

MachineOptions machine(const std::string& name, std::shared_ptr<MachinePort> port) {
  MachineOptions o;
  o.name = name;
  o.port = std::move(port);
  o.profiles_dir = cncstream::protocol::default_profiles_dir();
  return o;
}

// A program of `n` short moves that ends at X10 Y20 Z-1.
JobInput zigzag(int n) {
  JobInput j;
  j.file = "zigzag.nc";
  j.lines.push_back("G21 G90 G1 F2000");
  char buf[48];
  for (int i = 0; i < n; ++i) {
    std::snprintf(buf, sizeof buf, "X%d Y%d Z-1", i % 40, i % 7);
    j.lines.emplace_back(buf);
  }
  j.lines.push_back("X10 Y20");
  j.total_lines = static_cast<std::int64_t>(j.lines.size());
  return j;
}

// The port a test can swap: a simulator that comes back is a new one at the
// same link path, as a USB device re-enumerates under /dev/serial/by-id.
class SwappablePort final : public MachinePort {
 public:
  explicit SwappablePort(fs::path link) : link_(std::move(link)) {}
  std::shared_ptr<SimulatorPort> sim;
  std::string path() override { return link_.string(); }
  void opened() override {
    if (sim) sim->start();
  }

 private:
  fs::path link_;
};

}  // namespace

TEST(MachineSession, TwoMachinesOnOneThreadStreamAtOnceAndJogBetweenJobs) {
  boost::asio::io_context io;
  auto sim_a = std::make_shared<SimulatorPort>(SimulatorOptions{});
  auto sim_b = std::make_shared<SimulatorPort>(SimulatorOptions{});
  MachineSession a(io, machine("a", sim_a));
  MachineSession b(io, machine("b", sim_b));

  // A third party watching both machines.
  std::map<std::string, int> status_seen;
  std::map<std::string, JobOutcome> outcome;
  std::map<std::string, std::size_t> answered;
  auto watch = [&](MachineSession& s) {
    return s.subscribe([&, name = s.name()](const SessionEvent& e) {
      if (e.kind == SessionEventKind::Controller && e.controller.kind == EventKind::Status) ++status_seen[name];
      if (e.kind == SessionEventKind::JobEnded) {
        outcome[name] = e.outcome;
        answered[name] = e.lines_answered;
      }
    });
  };
  auto watch_a = watch(a);
  auto watch_b = watch(b);

  EXPECT_FALSE(a.start_job(zigzag(10)));  // not open yet: refused, with a reason
  a.open();
  b.open();
  ASSERT_TRUE(run_until(io, [&] { return a.ready() && b.ready(); }));

  // B runs a job; A, idle, jogs; B refuses a jog and a console line while its job runs.
  ASSERT_TRUE(b.start_job(zigzag(300)));
  const auto refused = b.jog_step(JogDirection{{1, 0, 0}}, 5, 1000);
  EXPECT_FALSE(refused.accepted);
  EXPECT_NE(refused.reason.find("job is running"), std::string::npos) << refused.reason;
  EXPECT_FALSE(b.console("G0 X0"));
  EXPECT_FALSE(b.start_job(zigzag(3)));  // one job at a time
  ASSERT_TRUE(a.jog_step(JogDirection{{1, 0, 0}}, 5, 1000));
  ASSERT_TRUE(run_until(io, [&] {
    const auto st = a.snapshot().status;
    return st && st->state == MachineState::Idle && st->mpos && std::abs((*st->mpos)[0] - 5.0) < 1e-6;
  })) << "the jog did not move machine a to X5";
  ASSERT_TRUE(run_until(io, [&] { return outcome.count("b"); }));
  EXPECT_EQ(outcome["b"], JobOutcome::Completed);

  // Now both stream at once, on this one thread.
  outcome.clear();
  const auto job_a = zigzag(2000), job_b = zigzag(1500);
  ASSERT_TRUE(a.start_job(job_a));
  ASSERT_TRUE(b.start_job(job_b));
  EXPECT_TRUE(a.job_active() && b.job_active());
  ASSERT_TRUE(run_until(io, [&] { return outcome.size() == 2; }));
  EXPECT_EQ(outcome["a"], JobOutcome::Completed);
  EXPECT_EQ(outcome["b"], JobOutcome::Completed);
  EXPECT_EQ(answered["a"], job_a.lines.size());
  EXPECT_EQ(answered["b"], job_b.lines.size());
  EXPECT_GT(status_seen["a"], 0);
  EXPECT_GT(status_seen["b"], 0);
  // Both machines stand where their programs end: no line was lost.
  for (MachineSession* s : {&a, &b}) {
    const auto st = s->snapshot().status;
    ASSERT_TRUE(st && st->mpos);
    EXPECT_NEAR((*st->mpos)[0], 10, 1e-6) << s->name();
    EXPECT_NEAR((*st->mpos)[1], 20, 1e-6) << s->name();
  }
  EXPECT_TRUE(a.close());
  EXPECT_TRUE(b.close());
  io.run_for(std::chrono::milliseconds(50));
  const auto ra = sim_a->finish(true), rb = sim_b->finish(true);
  EXPECT_FALSE(ra.overflowed);
  EXPECT_FALSE(rb.overflowed);
  // Every line the host sent was answered by the simulator (RX fidelity: nothing dropped).
  EXPECT_EQ(sim_a->lines_received(), sim_a->lines_answered());
  EXPECT_EQ(sim_b->lines_received(), sim_b->lines_answered());
}

TEST(MachineSession, AVanishedPortIsADisconnectAndTheReturnIsIdleNeverAResumedJob) {
  boost::asio::io_context io;
  const fs::path link = temp_dir() / "ttySIM0";
  const fs::path db = temp_dir() / "vanish.sqlite";
  fs::remove(db);
  auto port = std::make_shared<SwappablePort>(link);
  SimulatorOptions so;
  so.link = link;
  so.faults.vanish_after = 120;  // answers, then the pty goes away
  port->sim = std::make_shared<SimulatorPort>(so);

  auto opt = machine("router", port);
  opt.reconnect_interval_s = 0.05;
  MachineSession s(io, opt);
  JobJournal journal(s, db, link.string());
  std::vector<LinkState> links;
  std::optional<JobOutcome> ended;
  auto sub = s.subscribe([&](const SessionEvent& e) {
    if (e.kind == SessionEventKind::Link) links.push_back(e.link);
    if (e.kind == SessionEventKind::JobEnded) ended = e.outcome;
  });
  s.open();
  ASSERT_TRUE(run_until(io, [&] { return s.ready(); }));
  const auto job = zigzag(3000);
  ASSERT_TRUE(s.start_job(job));
  ASSERT_TRUE(run_until(io, [&] { return s.link() == LinkState::Disconnected; }));
  ASSERT_TRUE(ended);
  EXPECT_EQ(*ended, JobOutcome::Disconnected);
  EXPECT_FALSE(s.job_active());
  EXPECT_FALSE(s.jog_step(JogDirection{{1, 0, 0}}, 1, 100));  // nothing to command while disconnected

  const auto rec = journal.journal().job(journal.job_id());
  ASSERT_TRUE(rec && rec->outcome);
  EXPECT_EQ(*rec->outcome, "disconnected");
  const auto last = journal.journal().last_progress(journal.job_id());
  ASSERT_TRUE(last);
  EXPECT_GT(last->last_line, 0);
  EXPECT_LT(last->last_line, static_cast<std::int64_t>(job.lines.size()));

  // The session keeps trying the port while it is away.
  io.run_for(std::chrono::milliseconds(200));
  EXPECT_EQ(s.link(), LinkState::Disconnected);

  // The controller comes back at the same path: a new simulator.
  port->sim->finish(false);
  SimulatorOptions back;
  back.link = link;
  port->sim = std::make_shared<SimulatorPort>(back);
  ASSERT_TRUE(run_until(io, [&] { return s.ready(); }));
  ASSERT_TRUE(run_until(io, [&] {
    const auto st = s.snapshot().status;
    return st && st->state == MachineState::Idle;
  }));
  // Idle, and the job stays interrupted: nothing of it is sent again.
  io.run_for(std::chrono::milliseconds(300));
  EXPECT_FALSE(s.job_active());
  EXPECT_EQ(s.snapshot().progress.state, cncstream::protocol::JobState::None);
  EXPECT_EQ(journal.journal().jobs().size(), 1u);
  EXPECT_TRUE(s.close());
  io.run_for(std::chrono::milliseconds(50));
  port->sim->finish(false);
  EXPECT_LE(port->sim->lines_received(), 3u);  // identification and `$$`, no program line
  ASSERT_GE(links.size(), 4u);
  EXPECT_EQ(links[0], LinkState::Connecting);
  EXPECT_EQ(links[1], LinkState::Ready);
  EXPECT_EQ(links[2], LinkState::Disconnected);
}
