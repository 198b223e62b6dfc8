// MachineSession: routines outside a job (corner probing, the outline). The
// session feeds the routine the controller's answers, reports and status, and
// sends its lines one at a time as command lines; nothing else may move the
// machine meanwhile.
#include <fmt/core.h>

#include "cncstream/protocol/line_cleaner.hpp"
#include "cncstream/session/machine_session.hpp"

namespace cncstream::session {

using namespace protocol;

CommandResult MachineSession::refuse_during_routine(const char* what) const {
  if (!machine_routine_) return CommandResult::ok();
  return CommandResult::refused(fmt::format("{}: the {} is running; stop it first", what, machine_routine_->name()));
}

CommandResult MachineSession::run_routine(std::shared_ptr<MachineRoutine> routine) {
  const std::string what = routine ? std::string("run the ") + routine->name() : std::string("run a routine");
  if (!routine) return CommandResult::refused(what + ": none given");
  if (auto r = needs_engine(what.c_str()); !r) return r;
  if (engine_->profile().flow == FlowControl::SendResponse)
    return CommandResult::refused(what + ": not supported on " + profile_.id + " (GRBL family only: G38.x, $#)");
  if (job_active()) return CommandResult::refused(what + ": a job is running");
  if (machine_routine_) return refuse_during_routine(what.c_str());
  if (engine_->jogging()) return CommandResult::refused(what + ": a jog is running");
  if (auto r = refuse_in_alarm(what.c_str()); !r) return r;
  if (probe_pending_) return CommandResult::refused(what + ": probing Z; wait for it to finish");
  if (report_inches_)
    return CommandResult::refused(what + ": the controller reports in inches ($13=1): set $13=0 first");
  machine_routine_ = std::move(routine);
  machine_routine_line_.clear();
  log(std::string(machine_routine_->name()) + ": started");
  machine_routine_->start();
  // The routine waits for two idle reports before its first line: ask now.
  engine_->realtime(Realtime::StatusReport);
  drain();
  arm_timer();
  return CommandResult::ok();
}

void MachineSession::machine_routine_event(const Event& ev) {
  switch (ev.kind) {
    case EventKind::CommandAnswered:
      if (!machine_routine_line_.empty() && ev.line_text == machine_routine_line_) {
        machine_routine_line_.clear();
        machine_routine_->on_answer(!ev.info.has_value(), ev.code);
      }
      break;
    case EventKind::Info: machine_routine_->on_message(ev.text); break;
    case EventKind::Status:
      if (ev.status) machine_routine_->on_status(*ev.status);
      break;
    case EventKind::Alarm: machine_routine_->abort("alarm: " + ev.text); break;
    case EventKind::Reset: machine_routine_->abort("the controller was reset"); break;
    default: break;
  }
}

void MachineSession::pump_machine_routine() {
  if (!machine_routine_) return;
  if (auto p = machine_routine_->take_prompt()) {
    SessionEvent e;
    e.kind = SessionEventKind::Routine;
    e.text = *p;
    e.routine_prompt = *p;
    emit(e);
    if (!machine_routine_ || !engine_) return;
  }
  if (machine_routine_line_.empty() && !machine_routine_->finished()) {
    if (auto line = machine_routine_->take_line()) {
      std::string err;
      const auto cleaned = clean_gcode_line(*line, {}, &err);
      try {
        if (!cleaned) throw std::invalid_argument(err);
        machine_routine_line_ = *cleaned;
        engine_->send_command(*line);
      } catch (const std::exception& ex) {
        machine_routine_->abort(std::string("cannot send '") + *line + "': " + ex.what());
      }
    }
  }
  if (machine_routine_->finished()) end_machine_routine("");
}

void MachineSession::end_machine_routine(const std::string& why) {
  if (!machine_routine_) return;
  auto r = std::move(machine_routine_);
  machine_routine_line_.clear();
  if (!r->finished()) r->abort(why.empty() ? std::string("ended") : why);
  SessionEvent e;
  e.kind = SessionEventKind::Routine;
  e.routine_succeeded = r->succeeded();
  e.text = r->succeeded() ? r->summary() : r->failure();
  emit(e);
}

CommandResult MachineSession::routine_confirm() {
  if (!machine_routine_ || !machine_routine_->pending_prompt())
    return CommandResult::refused("confirm: no routine is waiting for the operator");
  machine_routine_->confirm();
  drain();
  arm_timer();
  return CommandResult::ok();
}

CommandResult MachineSession::routine_decline() {
  if (!machine_routine_ || !machine_routine_->pending_prompt())
    return CommandResult::refused("decline: no routine is waiting for the operator");
  machine_routine_->decline();
  drain();
  arm_timer();
  return CommandResult::ok();
}

}  // namespace cncstream::session
