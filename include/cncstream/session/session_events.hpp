#pragma once
// What a machine session tells its subscribers, and what it answers to a
// command. Controller events (status, answers, errors and alarms with their
// explanations) pass through verbatim; the session adds its own: the link
// coming and going, settings read, a job starting and ending.
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cncstream/protocol/engine.hpp"
#include "cncstream/protocol/status_report.hpp"
#include "cncstream/protocol/tool_change.hpp"
#include "cncstream/session/job_input.hpp"

namespace cncstream::session {

// Closed: never opened, or closed on purpose. Connecting: the port is open
// and the firmware is being identified and its settings read. Ready: the
// controller answers. Disconnected: the port went away (cable, power).
enum class LinkState { Closed, Connecting, Ready, Disconnected };
const char* to_string(LinkState s);

struct CommandResult {
  bool accepted = true;
  std::string reason;  // why it was refused
  static CommandResult ok() { return {}; }
  static CommandResult refused(std::string why) { return {false, std::move(why)}; }
  explicit operator bool() const { return accepted; }
};

enum class SessionEventKind {
  Link,        // the link changed state (text says why)
  Log,         // a line for the operator's log (opened, controller identified, warnings)
  Settings,    // `$$` was read
  Controller,  // a protocol event: status, line answered, error, alarm, job state...
  JobStarted,  // `job` points at the job's input (valid during the call)
  JobEnded,    // outcome, text and the last answered file line
  // A tool change: the routine asks the operator (`tool_prompt`), or it
  // ended (`tool_record`: done, skipped or failed); `text` says what.
  ToolChange,
  // A routine outside a job (corner probing, the outline, a tool routine): it
  // asks the operator (`routine_prompt`), or it ended (`routine_succeeded`; a
  // tool routine's `tool_record` too); `text` says what.
  Routine,
};

struct SessionEvent {
  SessionEventKind kind = SessionEventKind::Log;
  std::string text;
  double at = 0;  // the session's clock
  LinkState link = LinkState::Closed;
  protocol::Event controller;  // Controller
  const JobInput* job = nullptr;  // JobStarted, JobEnded
  protocol::JobOutcome outcome = protocol::JobOutcome::None;  // JobEnded
  long last_answered_line = 0;                                // JobEnded
  std::size_t lines_answered = 0;                             // JobEnded
  std::optional<protocol::ToolChangePrompt> tool_prompt;      // ToolChange
  std::optional<protocol::ToolChangeRecord> tool_record;      // ToolChange
  std::optional<protocol::RoutinePrompt> routine_prompt;      // Routine: the operator is asked
  std::optional<bool> routine_succeeded;                      // Routine: it ended
  std::string routine_name;                                   // Routine: which ("corner probe", "tool change", ...)
};

// What a display needs at any moment.
struct MachineSnapshot {
  std::string name;
  LinkState link = LinkState::Closed;
  double now = 0;
  std::string profile;  // "" until identified
  std::string banner;
  protocol::JobProgress progress;  // without the check errors
  std::optional<protocol::StatusReport> status;
  std::optional<std::array<int, 3>> overrides;
  protocol::ProtocolEngine::BufferUse buffer;
  bool alarm = false;
  bool jogging = false;
  bool job_active = false;
  // At a tool change: what the operator is asked now (nullopt: nothing).
  std::optional<protocol::ToolChangePrompt> tool_prompt;
  int tool_in_spindle = 0;  // as far as the session knows (0: unknown)
};

// Subscribers of one session. A handle removes its subscriber when dropped,
// also from inside a call (the list skips removed entries).
struct SubscriberList {
  std::vector<std::pair<std::uint64_t, std::function<void(const SessionEvent&)>>> entries;
  std::uint64_t next_id = 1;
  int depth = 0;  // emits in progress (a subscriber may cause another)
};

class Subscription {
 public:
  Subscription() = default;
  Subscription(std::weak_ptr<SubscriberList> list, std::uint64_t id) : list_(std::move(list)), id_(id) {}
  Subscription(Subscription&& o) noexcept : list_(std::move(o.list_)), id_(std::exchange(o.id_, 0)) {}
  Subscription& operator=(Subscription&& o) noexcept {
    if (this != &o) {
      reset();
      list_ = std::move(o.list_);
      id_ = std::exchange(o.id_, 0);
    }
    return *this;
  }
  ~Subscription() { reset(); }
  void reset();

 private:
  std::weak_ptr<SubscriberList> list_;
  std::uint64_t id_ = 0;
};

}  // namespace cncstream::session
