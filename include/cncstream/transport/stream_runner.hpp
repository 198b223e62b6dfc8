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
#include <vector>

#include "cncstream/protocol/engine.hpp"
#include "cncstream/protocol/grbl_settings.hpp"
#include "cncstream/protocol/identifier.hpp"
#include "cncstream/transport/serial_transport.hpp"

namespace cncstream::transport {

// What the operator's display needs, handed out at every tick.
struct RunnerSnapshot {
  double now = 0;  // seconds since the port opened
  std::string profile;
  protocol::JobProgress progress;
  std::optional<protocol::StatusReport> status;  // last status report (positions filled in)
  std::optional<std::array<int, 3>> overrides;    // last Ov: feed, rapid, spindle %
  std::size_t rx_in_flight = 0;   // bytes the host counts in the controller's RX buffer
  std::size_t rx_size = 0;        // the controller's RX buffer size (0: not character counting)
};

// A job to stream: the lines to send and, for each, the file line it stands
// for (so the journal and a later resume speak in file lines).
struct JobInput {
  std::filesystem::path file;      // journaled as the job's file
  std::string file_sha256;
  std::vector<std::string> lines;  // what to send, in order
  std::vector<long> source_lines;  // file line of each entry; empty: 1..n
  std::int64_t total_lines = 0;    // lines of the file
  std::int64_t resumed_from = 0;   // journal job this one resumes (0: none)
  std::int64_t from_line = 0;      // file line the resume continues after
};
// Reads a G-code file into a JobInput (hash, lines 1..n).
JobInput job_from_file(const std::filesystem::path& gcode_path);

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
  // GRBL family: read the controller's `$$` after identification (rates and
  // accelerations for the time estimate). The job starts once `ok` arrives.
  bool read_settings = true;
  double settings_timeout_s = 2.0;
  std::function<void(const protocol::GrblSettings&)> on_settings;
  std::function<void(const RunnerSnapshot&)> on_tick;  // every tick once the job started
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
  RunResult run(const JobInput& job);
  // Safe from a signal-watching thread or handler context: asks for a
  // controlled stop (hold, wait, reset) at the next tick.
  void request_stop() { stop_requested_ = true; }
  // Thread-safe operator requests, applied at the next tick: pause (feed
  // hold), resume (cycle start) and real-time bytes such as overrides. A byte
  // the identified firmware does not have is reported as a warning event.
  void request_pause() { enqueue(Request{Request::Pause, {}}); }
  void request_resume() { enqueue(Request{Request::Resume, {}}); }
  void request_toggle_pause() { enqueue(Request{Request::TogglePause, {}}); }
  void request_realtime(protocol::Realtime r) { enqueue(Request{Request::RealtimeByte, r}); }

 private:
  struct Request {
    enum Kind { Pause, Resume, TogglePause, RealtimeByte } kind;
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
