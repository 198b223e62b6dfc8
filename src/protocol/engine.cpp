#include "cncstream/protocol/engine.hpp"

namespace cncstream::protocol {

const char* to_string(EventKind k) {
  switch (k) {
    case EventKind::Warning: return "warning";
    case EventKind::Info: return "info";
    case EventKind::LineAnswered: return "line-answered";
    case EventKind::LineError: return "line-error";
    case EventKind::CheckError: return "check-error";
    case EventKind::Alarm: return "alarm";
    case EventKind::Status: return "status";
    case EventKind::Reset: return "reset";
    case EventKind::JobState: return "job-state";
    case EventKind::JobFinished: return "job-finished";
    case EventKind::CommandAnswered: return "command-answered";
  }
  return "?";
}

const char* to_string(JobState s) {
  switch (s) {
    case JobState::None: return "none";
    case JobState::Running: return "running";
    case JobState::Paused: return "paused";
    case JobState::HeldOnError: return "held-on-error";
    case JobState::Stopping: return "stopping";
    case JobState::Finished: return "finished";
    case JobState::ToolChange: return "tool-change";
  }
  return "?";
}

const char* to_string(JobOutcome o) {
  switch (o) {
    case JobOutcome::None: return "none";
    case JobOutcome::Completed: return "completed";
    case JobOutcome::Stopped: return "stopped";
    case JobOutcome::Error: return "error";
    case JobOutcome::Alarm: return "alarm";
    case JobOutcome::Disconnected: return "disconnected";
    case JobOutcome::CheckPassed: return "check-passed";
    case JobOutcome::CheckFailed: return "check-failed";
  }
  return "?";
}

}  // namespace cncstream::protocol

namespace cncstream::protocol {

std::string ProtocolEngine::jog_step(const JogDirection& dir, double distance_mm, double feed_mm_min, double now) {
  if (is_active(progress().state) && progress().state != JobState::ToolChange) return "jog: a job is running";
  std::string why = jog_.step(dir, distance_mm, feed_mm_min, now);
  pump_jog();
  return why;
}

std::string ProtocolEngine::jog_start(const JogDirection& dir, double feed_mm_min, double lease_s, double now) {
  if (is_active(progress().state) && progress().state != JobState::ToolChange) return "jog: a job is running";
  std::string why = jog_.start(dir, feed_mm_min, lease_s, now);
  pump_jog();
  return why;
}

void ProtocolEngine::jog_release() {
  jog_.release();
  pump_jog();
}

void ProtocolEngine::jog_cancel() {
  jog_.cancel_all();
  pump_jog();
}

}  // namespace cncstream::protocol
