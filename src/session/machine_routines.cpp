// MachineSession: routines outside a job (corner probing, the outline, the
// tool routines). The session feeds the routine the controller's answers,
// reports and status, and sends its lines one at a time as command lines;
// nothing else may move the machine meanwhile.
#include <fmt/core.h>

#include "cncstream/protocol/line_cleaner.hpp"
#include "cncstream/session/machine_session.hpp"

namespace cncstream::session {

using namespace protocol;

CommandResult MachineSession::refuse_during_routine(const char* what) const {
  if (!machine_routine_) return CommandResult::ok();
  return CommandResult::refused(fmt::format("{}: the {} is running; stop it first", what, machine_routine_->name()));
}

bool MachineSession::routine_operator_turn() const {
  return tool_routine_ && tool_routine_->pending_prompt();
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
  // Outside a job a hold is the operator stopping it: it ends, whatever it is.
  machine_routine_->set_hold_ends_it(true);
  log(std::string(machine_routine_->name()) + ": started");
  machine_routine_->start();
  // The routine waits for two idle reports before its first line: ask now.
  engine_->realtime(Realtime::StatusReport);
  drain();
  arm_timer();
  return CommandResult::ok();
}

void MachineSession::feed_routine(MachineRoutine& r, std::string& line_in_flight, const Event& ev) {
  switch (ev.kind) {
    case EventKind::CommandAnswered:
      if (!line_in_flight.empty() && ev.line_text == line_in_flight) {
        line_in_flight.clear();
        r.on_answer(!ev.info.has_value(), ev.code);
      }
      break;
    case EventKind::Info: r.on_message(ev.text); break;
    case EventKind::Status:
      if (ev.status) r.on_status(*ev.status);
      break;
    default: break;
  }
}

std::optional<std::string> MachineSession::controller_tool_change_refusal(const ToolChangeConfig& config) const {
  if (config.method != ToolChangeMethod::Controller) return std::nullopt;
  if (profile_.family != "grblhal" || !profile_.realtime_byte(Realtime::ToolChangeAck))
    return fmt::format("the tool-change method 'controller' is grblHAL's tool-change protocol (M6, its Tool state, "
                       "0xA3), and this controller is {} ({}); choose plate, sensor or manual",
                       profile_.id.empty() ? std::string("not identified") : profile_.id,
                       profile_.family == "grbl" ? "GRBL 1.1 answers M6 with error:20" : "no tool-change protocol in its profile");
  const auto it = settings_.find(341);
  if (it == settings_.end())
    return std::string("the tool-change method 'controller' needs grblHAL's $341 (tool-change mode), which the "
                       "controller did not report in $$");
  const int mode = static_cast<int>(it->second);
  if (mode == 4) return std::string("$341=4: the controller ignores M6; set $341=0 for the method 'controller'");
  if (mode != 0)
    return fmt::format("$341={}: the controller moves and touches off by itself at M6 ($TPW, the G59.3 sensor), "
                       "which this session does not drive; set $341=0 (the operator zeroes Z at our prompt) or "
                       "choose plate, sensor or manual",
                       mode);
  return std::nullopt;
}

bool MachineSession::in_controller_tool_state() const {
  const ToolChangeRoutine* r = routine_ ? routine_.get() : tool_routine_.get();
  if (!r || r->config().method != ToolChangeMethod::Controller || !r->pending_prompt()) return false;
  return true;
}

void MachineSession::send_routine_realtime(MachineRoutine& r) {
  for (const Realtime rt : r.take_realtime())
    if (!engine_->realtime(rt)) r.abort(fmt::format("{} has no real-time byte '{}'", profile_.id, realtime_key(rt)));
}

void MachineSession::send_routine_line(MachineRoutine& r, std::string& line_in_flight) {
  if (!line_in_flight.empty() || r.finished()) return;
  const auto line = r.take_line();
  if (!line) return;
  std::string err;
  const auto cleaned = clean_gcode_line(*line, {}, &err);
  try {
    if (!cleaned) throw std::invalid_argument(err);
    line_in_flight = *cleaned;
    engine_->send_command(*line);
  } catch (const std::exception& ex) {
    r.abort(std::string("cannot send '") + *line + "': " + ex.what());
  }
}

void MachineSession::machine_routine_event(const Event& ev) {
  feed_routine(*machine_routine_, machine_routine_line_, ev);
  if (ev.kind == EventKind::Alarm) machine_routine_->abort("alarm: " + ev.text);
  if (ev.kind == EventKind::Reset) machine_routine_->abort("the controller was reset");
}

void MachineSession::pump_machine_routine() {
  if (!machine_routine_) return;
  if (auto p = machine_routine_->take_prompt()) {
    SessionEvent e;
    e.kind = SessionEventKind::Routine;
    e.text = p->text;
    e.routine_prompt = *p;
    emit(e);
    if (!machine_routine_ || !engine_) return;
  }
  send_routine_realtime(*machine_routine_);
  send_routine_line(*machine_routine_, machine_routine_line_);
  if (machine_routine_->finished()) end_machine_routine("");
}

void MachineSession::end_machine_routine(const std::string& why) {
  if (!machine_routine_) return;
  auto r = std::move(machine_routine_);
  auto tool = std::move(tool_routine_);
  machine_routine_line_.clear();
  if (!r->finished()) r->abort(why.empty() ? std::string("ended") : why);
  SessionEvent e;
  e.kind = SessionEventKind::Routine;
  e.routine_succeeded = r->succeeded();
  e.routine_name = r->name();
  e.text = r->succeeded() ? r->summary() : r->failure();
  if (tool) {
    // The machine's tool and reference, as a job's change keeps them.
    const auto rec = tool->record();
    e.tool_record = rec;
    tool_in_spindle_ = rec.tool;
    if (tool->succeeded()) tool_reference_ = tool->reference();
    else if (tool->request().kind != ToolRoutineKind::CheckLength) forget_tool_reference("a failed tool routine");
    if (!rec.length_known) e.text += "; the length of the tool in the spindle is unknown";
  }
  emit(e);
}

MachineSession::ToolRoutineStart MachineSession::run_tool_routine(const ToolChangeConfig& config,
                                                                  ToolRoutineKind kind, int tool,
                                                                  double tolerance_mm) {
  ToolChangeRequest req;
  req.in_job = false;
  req.kind = kind;
  req.from_tool = tool_in_spindle_;
  req.to_tool = kind == ToolRoutineKind::Change ? tool : tool_in_spindle_;
  req.check_tolerance = tolerance_mm;
  if (kind == ToolRoutineKind::Change && tool <= 0)
    return {CommandResult::refused("change the tool: which tool (T1 or above)?"), nullptr};
  if (!(tolerance_mm > 0)) return {CommandResult::refused("check the tool: the tolerance must be above 0 mm"), nullptr};
  auto routine = std::make_shared<ToolChangeRoutine>(config, req, tool_reference_);
  if (machine_routine_) return {refuse_during_routine(routine->name()), nullptr};
  if (engine_)
    if (const auto why = controller_tool_change_refusal(config))
      return {CommandResult::refused(std::string(routine->name()) + ": " + *why), nullptr};
  // Set first: a routine that fails at its start ends inside run_routine.
  tool_routine_ = routine;
  if (auto r = run_routine(routine); !r) {
    tool_routine_.reset();
    return {r, nullptr};
  }
  // Failed at its start (nothing to compare with, a method that cannot do it): nothing moved.
  if (routine->finished() && !routine->succeeded()) return {CommandResult::refused(routine->failure()), routine};
  return {CommandResult::ok(), routine};
}

CommandResult MachineSession::set_tool_in_spindle(int tool) {
  if (tool < 0) return CommandResult::refused("tool in the spindle: T0 (unknown) or above");
  if (job_active()) return CommandResult::refused("tool in the spindle: a job is running");
  if (auto r = refuse_during_routine("tool in the spindle"); !r) return r;
  if (tool != tool_in_spindle_) forget_tool_reference("another tool was said to be in the spindle");
  tool_in_spindle_ = tool;
  return CommandResult::ok();
}

CommandResult MachineSession::routine_confirm() {
  if (!machine_routine_ || !machine_routine_->pending_prompt())
    return CommandResult::refused("confirm: no routine is waiting for the operator");
  // The routine's next move (safe Z, the probe) must not meet a jog still running.
  if (engine_ && engine_->jogging())
    return CommandResult::refused("confirm: a jog is running; wait until the machine is still");
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
