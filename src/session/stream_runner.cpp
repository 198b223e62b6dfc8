#include "cncstream/session/stream_runner.hpp"

#include <fmt/core.h>

#include <boost/asio/post.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>

#include <chrono>
#include <csignal>
#include <stdexcept>

#include "cncstream/protocol/response.hpp"
#include "cncstream/session/job_journal.hpp"
#include "cncstream/transport/sha256.hpp"

namespace cncstream::session {

using namespace protocol;

namespace {

// A port that also tells the caller when the session has opened it.
class HookedPort final : public MachinePort {
 public:
  HookedPort(std::shared_ptr<MachinePort> inner, std::function<void()> hook)
      : inner_(std::move(inner)), hook_(std::move(hook)) {}
  std::string path() override { return inner_->path(); }
  void opened() override {
    inner_->opened();
    hook_();
  }
  std::string describe() override { return inner_->describe(); }

 private:
  std::shared_ptr<MachinePort> inner_;
  std::function<void()> hook_;
};

}  // namespace

JobInput job_from_file(const std::filesystem::path& gcode_path) {
  JobInput j;
  j.file = gcode_path;
  j.lines = read_gcode_lines(gcode_path.string());
  j.file_sha256 = transport::sha256_file(gcode_path);
  j.total_lines = static_cast<std::int64_t>(j.lines.size());
  return j;
}

StreamRunner::StreamRunner(RunnerOptions opt) : opt_(std::move(opt)) {}
StreamRunner::~StreamRunner() = default;

void StreamRunner::post(std::function<void(MachineSession&)> fn) {
  std::lock_guard<std::mutex> l(mu_);
  if (!io_) return;
  boost::asio::post(*io_, [this, fn = std::move(fn)] {
    if (session_) fn(*session_);
  });
}

void StreamRunner::request_stop() {
  stop_before_start_ = true;
  post([](MachineSession& s) { s.stop(); });
}
void StreamRunner::request_pause() {
  post([](MachineSession& s) { s.hold(); });
}
void StreamRunner::request_resume() {
  post([](MachineSession& s) { s.resume(); });
}
void StreamRunner::request_toggle_pause() {
  post([](MachineSession& s) { s.toggle_hold(); });
}
void StreamRunner::request_realtime(Realtime r) {
  post([this, r](MachineSession& s) {
    if (auto res = s.realtime(r); !res && opt_.on_event) opt_.on_event(Event{EventKind::Warning, res.reason});
  });
}

void StreamRunner::request_tool_change_answer(bool confirm) {
  post([this, confirm](MachineSession& s) {
    const auto r = confirm ? s.tool_change_confirm() : s.tool_change_decline();
    if (!r && opt_.on_log) opt_.on_log(r.reason);
  });
}

RunResult StreamRunner::run(const std::filesystem::path& gcode_path) { return run(job_from_file(gcode_path)); }

RunResult StreamRunner::run(const JobInput& job) {
  boost::asio::io_context io;
  MachineOptions mo;
  mo.port = opt_.machine_port ? opt_.machine_port : std::make_shared<DevicePort>(opt_.port);
  const std::string port_label = opt_.machine_port ? opt_.machine_port->path() : opt_.port;
  if (opt_.on_port_opened) mo.port = std::make_shared<HookedPort>(mo.port, opt_.on_port_opened);
  mo.serial = opt_.serial;
  mo.profiles_dir = opt_.profiles_dir;
  mo.force_profile = opt_.force_profile;
  mo.identify = opt_.identify;
  mo.read_settings = opt_.read_settings;
  mo.settings_timeout_s = opt_.settings_timeout_s;
  mo.tool_change = opt_.tool_change;
  MachineSession session(io, mo);
  std::unique_ptr<JobJournal> journal;
  if (opt_.journal_path) journal = std::make_unique<JobJournal>(session, *opt_.journal_path, port_label, opt_.progress_interval_s);

  RunResult result;
  bool started = false, done = false;
  std::exception_ptr failure;
  boost::asio::steady_timer ticker(io), deadline(io);
  boost::asio::signal_set signals(io);

  std::optional<MachineSnapshot> final_snapshot;  // the machine as the job ended, before the port closed
  auto finish = [&](JobOutcome o, const std::string& msg) {
    if (done) return;
    done = true;
    result.outcome = o;
    result.message = msg;
    ticker.cancel();
    deadline.cancel();
    signals.cancel();
    if (session.job_active()) {
      // Gave up with the job running: report how far it got (the port closes below without a job end).
      const MachineSnapshot snap = session.snapshot();
      result.lines_answered = snap.progress.lines_answered;
      result.last_answered_line = snap.progress.last_answered_line;
      return;
    }
    if (started) final_snapshot = session.snapshot();
    session.close();                   // the loop ends when the last byte is out
  };

  auto sub = session.subscribe([&](const SessionEvent& e) {
    try {
      switch (e.kind) {
        case SessionEventKind::Log:
          if (opt_.on_log) opt_.on_log(e.text);
          break;
        case SessionEventKind::Settings:
          if (opt_.on_settings) opt_.on_settings(session.settings());
          break;
        case SessionEventKind::Controller:
          if (opt_.on_event) opt_.on_event(e.controller);
          break;
        case SessionEventKind::ToolChange:
          if (opt_.on_tool_change) opt_.on_tool_change(e);
          break;
        case SessionEventKind::Link:
          if (e.link == LinkState::Ready && !started) {
            started = true;
            result.profile = session.snapshot().profile;
            if (auto r = session.start_job(job, opt_.mode); !r) throw std::invalid_argument(r.reason);
            if (journal) result.job_id = journal->job_id();
            if (stop_before_start_.exchange(false)) session.stop();
          } else if (e.link == LinkState::Disconnected && !done) {
            finish(JobOutcome::Disconnected, e.text + "; last answered file line " +
                                                 std::to_string(result.last_answered_line));
          }
          break;
        case SessionEventKind::JobEnded:
          result.lines_answered = e.lines_answered;
          result.last_answered_line = e.last_answered_line;
          finish(e.outcome, e.text);
          break;
        default: break;
      }
    } catch (...) {
      if (!failure) failure = std::current_exception();
      io.stop();
    }
  });

  auto report = [&] {
    if (!opt_.on_tick || !started) return;
    opt_.on_tick(session.snapshot());
  };
  std::function<void()> tick = [&] {
    ticker.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(opt_.tick_s)));
    ticker.async_wait([&](const boost::system::error_code& ec) {
      if (ec || done) return;
      report();
      tick();
    });
  };
  if (opt_.max_run_s > 0) {
    deadline.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(opt_.max_run_s)));
    deadline.async_wait([&](const boost::system::error_code& ec) {
      if (ec || done) return;
      finish(JobOutcome::Error, fmt::format("gave up after {:g} s", opt_.max_run_s));
      io.stop();
    });
  }

  int interrupts = 0;
  std::function<void()> watch_sigint = [&] {
    signals.async_wait([&](const boost::system::error_code& ec, int) {
      if (ec) return;
      if (++interrupts >= 2) {
        signals.clear();  // SIGINT's default action again
        return;
      }
      if (opt_.on_log) opt_.on_log("stop requested: holding, then resetting once motion has stopped");
      if (started) session.stop();
      else stop_before_start_ = true;
      watch_sigint();
    });
  };
  if (opt_.stop_on_sigint) {
    signals.add(SIGINT);
    watch_sigint();
  }
  {
    std::lock_guard<std::mutex> l(mu_);
    io_ = &io;
    session_ = &session;
  }
  try {
    session.open();
    tick();
    io.run();
  } catch (...) {
    if (!failure) failure = std::current_exception();
  }
  {
    std::lock_guard<std::mutex> l(mu_);
    io_ = nullptr;
    session_ = nullptr;
  }
  if (!failure && opt_.on_tick && started) opt_.on_tick(final_snapshot ? *final_snapshot : session.snapshot());
  result.bytes_written = session.bytes_written();
  result.seconds = session.now();
  if (journal && result.job_id && session.job_active()) {
    // Gave up or failed with the job still running: its record ends here,
    // with an end row that says how far it got.
    journal->end_now(failure ? "error" : to_string(result.outcome), failure ? "runner failure" : result.message);
  }
  stop_before_start_ = false;  // a stop asked for this run does not carry over to the next
  if (failure) std::rethrow_exception(failure);
  if (!done) {
    // The loop ran dry without a job end (the port closed before identification finished).
    result.outcome = JobOutcome::Disconnected;
    if (result.message.empty()) result.message = "the controller went away before the job started";
  }
  return result;
}

}  // namespace cncstream::session
