#pragma once
// Ties it together for `cncstream FILE PORT`: serial transport, firmware
// identification, the protocol engine, and the journal, on one Asio event loop
// (single thread; the engine stays a pure state machine driven from here).
#include <atomic>
#include <filesystem>
#include <functional>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "cncstream/protocol/engine.hpp"
#include "cncstream/protocol/identifier.hpp"
#include "cncstream/transport/serial_transport.hpp"

namespace cncstream::transport {

struct RunnerOptions {
  std::string port;  // device path (resolve "auto" with choose_auto_port first)
  SerialSettings serial;
  std::filesystem::path profiles_dir;
  std::optional<std::string> force_profile;  // skip identification's choice (still waits for the banner)
  protocol::IdentifyOptions identify;
  protocol::JobMode mode = protocol::JobMode::Run;
  std::optional<std::filesystem::path> journal_path;  // nullopt: no journal
  double tick_s = 0.02;
  double progress_interval_s = 0.1;  // journal rows at least this often while lines are answered
  double max_run_s = 0;              // 0: no limit (tests set one)
  std::function<void(const protocol::Event&)> on_event;
  std::function<void(const std::string&)> on_log;
  std::function<void()> on_port_opened;  // e.g. a test's fake controller "resets" here
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
  // Blocking: streams `gcode_path` and returns how the job ended. Throws for
  // bad input (unreadable file, lines too long for the controller, no port).
  RunResult run(const std::filesystem::path& gcode_path);
  // Safe from a signal-watching thread or handler context: asks for a
  // controlled stop (hold, wait, reset) at the next tick.
  void request_stop() { stop_requested_ = true; }
  // Thread-safe operator requests, applied at the next tick: pause (feed
  // hold), resume (cycle start) and real-time bytes such as overrides. A byte
  // the identified firmware does not have is reported as a warning event.
  void request_pause() { enqueue(Request{Request::Pause, {}}); }
  void request_resume() { enqueue(Request{Request::Resume, {}}); }
  void request_realtime(protocol::Realtime r) { enqueue(Request{Request::RealtimeByte, r}); }

 private:
  struct Request {
    enum Kind { Pause, Resume, RealtimeByte } kind;
    protocol::Realtime realtime;
  };
  void enqueue(Request r) {
    std::lock_guard<std::mutex> l(mu_);
    requests_.push_back(r);
  }
  RunnerOptions opt_;
  std::atomic<bool> stop_requested_{false};
  std::mutex mu_;
  std::deque<Request> requests_;
};

}  // namespace cncstream::transport
