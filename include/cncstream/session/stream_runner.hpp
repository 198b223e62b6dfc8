#pragma once
// One job from start to end, for a terminal program or a test: a machine
// session on its own io_context, opened, given the job, and closed when the
// job ends. A front end of the session like any other (the journal and the
// display subscribe to it); the daemon keeps its sessions open instead.
#include <array>
#include <atomic>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "cncstream/protocol/engine.hpp"
#include "cncstream/protocol/grbl_settings.hpp"
#include "cncstream/protocol/identifier.hpp"
#include "cncstream/session/job_input.hpp"
#include "cncstream/session/machine_port.hpp"
#include "cncstream/session/machine_session.hpp"
#include "cncstream/transport/serial_transport.hpp"

namespace cncstream::session {

struct RunnerOptions {
  std::string port;                   // device path (resolve "auto" with choose_auto_port first)
  std::shared_ptr<MachinePort> machine_port;  // instead of `port`: e.g. the in-process simulator
  transport::SerialSettings serial;
  std::filesystem::path profiles_dir;
  std::optional<std::string> force_profile;
  protocol::IdentifyOptions identify;
  protocol::JobMode mode = protocol::JobMode::Run;
  std::optional<std::filesystem::path> journal_path;  // nullopt: no journal
  double tick_s = 0.1;               // display ticks (on_tick)
  double progress_interval_s = 0.1;  // journal rows at least this often while lines are answered
  double max_run_s = 0;              // 0: no limit (tests set one)
  std::function<void(const protocol::Event&)> on_event;
  std::function<void(const std::string&)> on_log;
  std::function<void()> on_port_opened;  // e.g. a test's fake controller "resets" here
  bool read_settings = true;
  double settings_timeout_s = 2.0;
  std::function<void(const protocol::GrblSettings&)> on_settings;
  std::function<void(const MachineSnapshot&)> on_tick;
  // Ctrl-C asks for a controlled stop (hold, wait, reset); a second one
  // gives SIGINT back to the system, so a third ends the process.
  bool stop_on_sigint = false;  // every tick once the job started, and once at the end
  // Tool changes run by the session (nullopt: M0/M6 go to the controller),
  // and what it asks or reports at them (on the session's thread).
  std::optional<protocol::ToolChangeConfig> tool_change;
  std::function<void(const SessionEvent&)> on_tool_change;
};

struct RunResult {
  protocol::JobOutcome outcome = protocol::JobOutcome::None;
  std::string message;
  std::string profile;
  std::int64_t job_id = 0;
  std::size_t lines_answered = 0;
  long last_answered_line = 0;
  std::size_t bytes_written = 0;
  double seconds = 0;
};

class StreamRunner {
 public:
  explicit StreamRunner(RunnerOptions opt);
  ~StreamRunner();
  // Blocking: streams the job and returns how it ended. Throws for bad input
  // (unreadable file, lines the controller cannot take, a port that does not open).
  RunResult run(const std::filesystem::path& gcode_path);
  RunResult run(const JobInput& job);
  // From any thread (a key reader, a signal watcher): posted to the
  // session's event loop. Before the session exists they are kept and
  // applied once the job starts.
  void request_stop();
  void request_pause();
  void request_resume();
  void request_toggle_pause();
  void request_realtime(protocol::Realtime r);
  // The operator's answer at a tool change's prompt.
  void request_tool_change_answer(bool confirm);
  // Anything else the operator does on the session (a console line at a
  // tool change's prompt), on its thread, in order with the requests above.
  void request_on_session(std::function<void(MachineSession&)> fn) { post(std::move(fn)); }

 private:
  void post(std::function<void(MachineSession&)> fn);
  RunnerOptions opt_;
  std::mutex mu_;
  boost::asio::io_context* io_ = nullptr;  // while run() runs
  MachineSession* session_ = nullptr;
  std::atomic<bool> stop_before_start_{false};
};

}  // namespace cncstream::session
