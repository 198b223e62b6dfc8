#pragma once
// What a protocol engine reports, and the interface the runner drives. Engines
// are pure state machines: bytes in (on_bytes), time passed in (tick), bytes
// out (take_output) and events out (take_events). No I/O, no threads, no clocks.
#include <optional>
#include <utility>
#include <string>
#include <string_view>
#include <vector>

#include "cncstream/gcode/interpreter.hpp"
#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/protocol/jog.hpp"
#include "cncstream/protocol/jog_engine.hpp"
#include "cncstream/protocol/line_cleaner.hpp"
#include "cncstream/protocol/status_report.hpp"

namespace cncstream::protocol {

enum class EventKind {
  Warning,       // something odd but handled (stale ok, unparsable line)
  Info,          // controller messages worth showing ([MSG:..], echo:)
  LineAnswered,  // a file line got `ok`
  LineError,     // a file line got `error:N` / was rejected
  CheckError,    // the check pass ($C) rejected a file line (nothing moved; the pass goes on)
  Alarm,         // ALARM:N
  Status,        // a parsed status report
  Reset,         // the controller restarted (banner seen)
  JobState,      // the job changed state (text says to what)
  JobFinished,   // the job ended (text: outcome)
  CommandAnswered,  // an operator command got ok / error
};
const char* to_string(EventKind k);

struct Event {
  Event() = default;
  Event(EventKind k, std::string t) : kind(k), text(std::move(t)) {}
  EventKind kind = EventKind::Info;
  std::string text;         // human-readable summary
  long source_line = 0;     // file line (1-based) when the event is about one
  std::string line_text;    // the cleaned line sent
  int code = 0;             // error / alarm code
  std::optional<CodeInfo> info;  // meaning and advice for error / alarm
  std::optional<StatusReport> status;
};

// CheckThenRun: a check pass ($C) first; the job streams only if it found no
// error (progress().mode is Check during the pass, Run after).
enum class JobMode { Run, Check, CheckThenRun };
// ToolChange: stopped at a tool change (every line before it answered);
// the session runs its routine with commands, then continues the job.
enum class JobState { None, Running, Paused, HeldOnError, Stopping, Finished, ToolChange };
const char* to_string(JobState s);
// A job that has started and not finished (running, paused, held, stopping).
inline bool is_active(JobState s) {
  return s == JobState::Running || s == JobState::Paused || s == JobState::HeldOnError || s == JobState::Stopping ||
         s == JobState::ToolChange;
}

enum class JobOutcome { None, Completed, Stopped, Error, Alarm, Disconnected, CheckPassed, CheckFailed };
const char* to_string(JobOutcome o);

struct JobProgress {
  JobState state = JobState::None;
  JobOutcome outcome = JobOutcome::None;
  JobMode mode = JobMode::Run;
  std::size_t total_lines = 0;       // file lines
  std::size_t lines_sent = 0;        // file lines handed to the controller (blank ones count when passed)
  std::size_t lines_answered = 0;    // file lines answered ok (or skipped as blank) in order
  long last_answered_line = 0;       // 1-based file line of the last answered one, 0 = none
  // 1-based file line the machine is estimated to be executing (answered
  // lines less the planner's queue: execution_estimate.hpp); what progress
  // and ETA shown to an operator follow. 0 = none yet.
  long executing_line = 0;
  std::vector<Event> check_errors;   // check mode: every error with its line
};

class ProtocolEngine {
 public:
  virtual ~ProtocolEngine() = default;
  virtual void on_bytes(std::string_view bytes, double now) = 0;
  virtual void tick(double now) = 0;
  std::string take_output() { return std::exchange(output_, {}); }
  std::vector<Event> take_events() { return std::exchange(events_, {}); }

  // Starts streaming a prepared program. Throws std::logic_error if a job is
  // already active or the program has errors.
  virtual void start_job(PreparedProgram program, JobMode mode, double now) = 0;
  virtual void pause() = 0;
  virtual void resume() = 0;
  // The operator's one key: resume if the job (or the machine) is holding,
  // else pause.
  virtual void toggle_pause() {
    if (progress().state == JobState::Paused || progress().state == JobState::HeldOnError) resume();
    else pause();
  }
  virtual void stop() = 0;  // controlled stop: hold, wait for motion to stop, reset
  // Tool changes (lines marked PreparedLine::tool_change): the job stops in
  // JobState::ToolChange at such a line once every line before it is
  // answered; tool_change_done() counts it as done (never sent) and goes on.
  // Engines without them never stop there.
  struct ToolChangeStop {
    long source_line = 0;
    int tool = 0;
  };
  virtual std::optional<ToolChangeStop> tool_change_stop() const { return std::nullopt; }
  virtual void tool_change_done() {}
  // Ends the job as an error with this reason (a controlled stop: hold, reset).
  virtual void abort_job(const std::string& why) {
    (void)why;
    stop();
  }
  // An operator command line (e.g. "$X", "$H", "G0 X0"); queued behind the job.
  virtual void send_command(const std::string& line) = 0;
  // The controller went away (EOF/EIO): ends any job as Disconnected.
  virtual void disconnected() = 0;

  // A real-time command (overrides, hold, status...); false if this
  // controller has no such byte (nothing is sent then).
  virtual bool realtime(Realtime r) = 0;

  // Jogging (jog_engine.hpp), only while no job runs. Each request returns
  // "" when accepted, else why not. A step moves `distance_mm` along `dir`
  // (at most JogConfig::max_steps queued); a continuous jog runs while its
  // holder renews it within lease_s, and jog_release() stops the motion at
  // once (GRBL: jog cancel 0x85; Marlin: M410 quick stop).
  std::string jog_step(const JogDirection& dir, double distance_mm, double feed_mm_min, double now);
  std::string jog_start(const JogDirection& dir, double feed_mm_min, double lease_s, double now);
  bool jog_renew(double now) { return jog_.renew(now); }
  void jog_release();
  void jog_cancel();  // steps too: a stop
  bool jogging() const { return jog_.busy(); }
  const JogEngine& jog() const { return jog_; }
  void set_jog_limits(const JogLimits& l) { jog_.set_limits(l); }

  virtual const FirmwareProfile& profile() const = 0;
  virtual const JobProgress& progress() const = 0;
  virtual bool busy() const = 0;  // lines or commands still in flight or queued
  // The modal state after the last answered file line (the G-code
  // interpreter's own state: one modal state for the whole project).
  virtual const gcode::ParserState& modal() const = 0;
  // The last status report with positions completed (nullopt: none yet, or
  // a controller that is not polled) and the override percentages.
  virtual std::optional<StatusReport> status() const { return std::nullopt; }
  virtual std::optional<std::array<int, 3>> overrides() const { return std::nullopt; }
  // Bytes (GRBL) or lines (Marlin) in the controller's receive queue, and how many fit.
  struct BufferUse {
    std::size_t in_flight = 0, capacity = 0;
    bool bytes = true;
  };
  virtual BufferUse buffer() const = 0;
  // The next time tick() has work (status poll, time-out), in the engine's
  // clock; +infinity when nothing is due. The caller arms a timer for it:
  // no polling loop.
  virtual double next_deadline() const = 0;

 protected:
  explicit ProtocolEngine(JogConfig jog = {}) : jog_(jog) {}
  // Sends what the jog engine has due (the family's line format) and its notes.
  virtual void pump_jog() = 0;
  void emit_jog_notes() {
    for (auto& n : jog_.take_notes()) emit({EventKind::Warning, std::move(n)});
  }
  void emit(Event e) { events_.push_back(std::move(e)); }
  void write(std::string_view bytes) { output_.append(bytes); }
  std::string output_;
  std::vector<Event> events_;
  JogEngine jog_;
};

}  // namespace cncstream::protocol
