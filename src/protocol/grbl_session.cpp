#include "cncstream/protocol/grbl_session.hpp"

#include <fmt/core.h>

#include "cncstream/protocol/pattern.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace cncstream::protocol {

namespace {

constexpr double kResetTimeout = 3.0;  // banner expected within this after 0x18
constexpr double kDrainPollInterval = 0.2;  // status requests while the last moves run out
// An idle controller answers a line at once; after this long (plus the
// line's own dwell) its silence means the line, or its answer, was lost.
constexpr double kSilenceLimit = 10.0;

std::string describe(const CodeInfo& c, const char* kind) {
  return std::string(kind) + std::to_string(c.code) + " (" + c.name + "): " + c.text + " What to do: " + c.action;
}

}  // namespace

GrblSession::GrblSession(FirmwareProfile profile, GrblSessionOptions opt)
    : profile_(std::move(profile)),
      opt_(opt),
      counter_(profile_.rx_buffer_size, opt.rx_margin.value_or(profile_.rx_margin)) {
  if (profile_.flow != FlowControl::CharacterCounting)
    throw std::invalid_argument("GrblSession needs a character-counting profile, not '" + profile_.id + "'");
  for (const auto& l : profile_.startup_lines) {
    PreparedLine p;
    p.text = l;
    p.sync = true;
    commands_.emplace_back(std::move(p), Origin::Command);
  }
}

bool GrblSession::busy() const {
  return counter_.in_flight_count() > 0 || !commands_.empty() || is_active(progress_.state) || expect_reset_;
}

std::size_t GrblSession::in_flight_of(Origin o) const {
  return static_cast<std::size_t>(std::count(in_flight_origin_.begin(), in_flight_origin_.end(), o));
}

void GrblSession::on_bytes(std::string_view bytes, double now) {
  now_ = now;
  splitter_.feed(bytes, [&](std::string_view line) { on_line(line, now); });
  pump();
}

void GrblSession::tick(double now) {
  now_ = now;
  if (opt_.poll_status && now >= next_poll_) {
    const auto q = profile_.realtime_byte(Realtime::StatusReport).value_or('?');
    write(std::string(1, static_cast<char>(q)));
    next_poll_ = now + profile_.status_poll_interval_s;
  }
  if (draining_ && progress_.state == JobState::Running && !expect_reset_ && now >= drain_poll_at_) {
    write(std::string(1, static_cast<char>(profile_.realtime_byte(Realtime::StatusReport).value_or('?'))));
    drain_poll_at_ = now + kDrainPollInterval;
  }
  if (expect_reset_ && now >= reset_deadline_) {
    emit({EventKind::Warning, "no banner within 3 s after the soft reset; assuming the controller restarted"});
    on_banner();
  }
  jog_.tick(now);
  pump_jog();
}

void GrblSession::on_line(std::string_view line, double now) {
  now_ = now;
  const Response r = parse_response(line);
  if (!r.parse_error.empty()) emit({EventKind::Warning, r.parse_error});
  switch (r.kind) {
    case ResponseKind::Empty: return;
    case ResponseKind::Ok: on_answer(true, 0, now); return;
    case ResponseKind::Error: on_answer(false, r.code, now); return;
    case ResponseKind::Status:
      if (r.status) on_status(*r.status);
      return;
    case ResponseKind::Alarm: {
      const CodeInfo info = profile_.alarm_info(r.code);
      Event e{EventKind::Alarm, describe(info, "ALARM:")};
      e.code = r.code;
      e.info = info;
      e.source_line = progress_.last_answered_line;
      emit(e);
      jog_.forget();  // an alarm ends every jog in the controller
      if (is_active(progress_.state))
        finish_job(JobOutcome::Alarm, "job stopped by ALARM:" + std::to_string(r.code) + " after file line " +
                                          std::to_string(progress_.last_answered_line) + " was answered. " +
                                          info.action);
      if (info.reset_required && !expect_reset_) soft_reset();
      return;
    }
    case ResponseKind::Message:
    case ResponseKind::ParserState:
    case ResponseKind::Feedback:
    case ResponseKind::Version:
    case ResponseKind::Options:
      emit({EventKind::Info, r.line});
      return;
    case ResponseKind::StartupEcho:
      if (r.code > 0)
        emit({EventKind::Warning, "startup line '" + r.body + "' failed: " +
                                      describe(profile_.error_info(r.code), "error:") +
                                      " (fix or clear it with $N0= / $N1=)"});
      else
        emit({EventKind::Info, "startup line executed: " + r.line});
      return;
    default: break;
  }
  const bool banner =
      matches_any_pattern(profile_.banner_patterns, r.body) ||
      r.body.rfind("Grbl ", 0) == 0 || r.body.rfind("GrblHAL ", 0) == 0;
  if (banner) {
    on_banner();
    return;
  }
  emit({EventKind::Info, r.line});
}

void GrblSession::on_answer(bool ok, int code, double) {
  waiting_since_ = now_;
  silence_reported_ = false;
  auto line = counter_.answer();
  if (!line) {
    emit({EventKind::Warning, std::string("'") + (ok ? "ok" : "error:" + std::to_string(code)) +
                                  "' arrived with no line in flight (stale answer around a reset); ignored"});
    return;
  }
  const Origin origin = in_flight_origin_.front();
  in_flight_origin_.pop_front();
  switch (origin) {
    case Origin::File: {
      if (!is_active(progress_.state)) {
        // Lines still in the controller's buffer when an alarm ended the job
        // get error:9 (locked) or the like: they ran nowhere, so they are
        // not progress and not new errors.
        emit({EventKind::Info, "file line " + std::to_string(line->source_line) + " answered '" +
                                   (ok ? std::string("ok") : "error:" + std::to_string(code)) +
                                   "' after the job had ended; not counted"});
        break;
      }
      progress_.last_answered_line = line->source_line;
      if (ok) {
        ++progress_.lines_answered;
        apply_answered_line(modal_, line->text);
        execution_.on_answered(line->source_line, line->text);
        if (progress_.mode == JobMode::Check) execution_.all_done();  // nothing moves in a check
        progress_.executing_line = execution_.executing_line();
        Event e{EventKind::LineAnswered, "ok"};
        e.source_line = line->source_line;
        e.line_text = line->text;
        emit(std::move(e));
        break;
      }
      const CodeInfo info = profile_.error_info(code);
      Event e{EventKind::LineError, "line " + std::to_string(line->source_line) + " '" + line->text +
                                        "': " + describe(info, "error:")};
      e.source_line = line->source_line;
      e.line_text = line->text;
      e.code = code;
      e.info = info;
      if (progress_.mode == JobMode::Check) {
        e.kind = EventKind::CheckError;
        progress_.check_errors.push_back(e);
        error_seen_ = true;
        emit(std::move(e));
        break;
      }
      emit(e);
      if (progress_.state == JobState::Running || progress_.state == JobState::Paused) {
        // Lines already in the controller's buffer keep running: hold the
        // motion now so the operator decides with the machine stopped.
        error_seen_ = true;
        write(std::string(1, static_cast<char>(profile_.realtime_byte(Realtime::FeedHold).value_or('!'))));
        hold_sent_ = true;
        set_job_state(JobState::HeldOnError, "held after error on line " + std::to_string(line->source_line) +
                                                 "; resume to continue after it, or stop");
      }
      break;
    }
    case Origin::Command: {
      Event e{EventKind::CommandAnswered, line->text + ": ok"};
      e.line_text = line->text;
      if (!ok) {
        e.info = profile_.error_info(code);
        e.code = code;
        e.text = line->text + ": " + describe(*e.info, "error:");
      }
      emit(std::move(e));
      break;
    }
    case Origin::Jog:
      jog_.on_answer(ok, ok ? std::string() : describe(profile_.error_info(code), "error:"), now_);
      emit_jog_notes();
      break;
    case Origin::CheckToggle:
      if (check_phase_ == CheckPhase::Entering) {
        if (ok) {
          check_phase_ = CheckPhase::Streaming;
        } else {
          const CodeInfo info = profile_.error_info(code);
          finish_job(JobOutcome::CheckFailed, "could not enter check mode ($C): " + describe(info, "error:"));
        }
      }
      break;
  }
  maybe_complete();
}

void GrblSession::maybe_complete() {
  if (progress_.state != JobState::Running && progress_.state != JobState::HeldOnError) return;
  if (next_index_ < program_.lines.size() || in_flight_of(Origin::File) > 0) return;
  if (progress_.state == JobState::HeldOnError) return;  // the operator decides
  if (progress_.mode == JobMode::Run) {
    if (draining_) return;
    draining_ = true;
    idle_reports_ = 0;
    drain_poll_at_ = now_;  // ask for a status at the next tick
    emit({EventKind::Info, "all " + std::to_string(progress_.total_lines) +
                               " lines answered; waiting for the machine to finish its moves"});
  } else if (check_phase_ == CheckPhase::Streaming) {
    // Leaving $C soft-resets the controller: expect a banner.
    check_phase_ = CheckPhase::Leaving;
    PreparedLine l;
    l.text = "$C";
    l.sync = true;
    commands_.emplace_front(std::move(l), Origin::CheckToggle);
  }
}

void GrblSession::on_banner() {
  counter_.clear();
  in_flight_origin_.clear();
  jog_.forget();
  const bool leaving_check = check_phase_ == CheckPhase::Leaving;
  const bool expected = expect_reset_ || leaving_check;
  expect_reset_ = false;
  hold_sent_ = false;
  emit({EventKind::Reset, leaving_check ? "controller restarted on leaving check mode ($C), as GRBL does"
                          : expected    ? "controller restarted after our soft reset"
                                        : "controller restarted unexpectedly (reset button, power or a crash)"});
  if (check_phase_ == CheckPhase::Leaving) {
    check_phase_ = CheckPhase::None;
    const auto n = progress_.check_errors.size();
    if (n == 0 && run_after_check_ && progress_.state == JobState::Running) {
      emit({EventKind::JobState, "check pass found no errors: streaming the job"});
      PreparedProgram program = std::move(program_);
      progress_.state = JobState::None;
      start_job(std::move(program), JobMode::Run, now_);
      return;
    }
    finish_job(n == 0 ? JobOutcome::CheckPassed : JobOutcome::CheckFailed,
               n == 0 ? "check pass found no errors" : "check pass found " + std::to_string(n) + " error(s)");
    return;
  }
  if (!is_active(progress_.state)) return;
  if (stop_requested_) {
    finish_job(error_seen_ ? JobOutcome::Error : JobOutcome::Stopped,
               (abort_reason_.empty() ? std::string() : abort_reason_ + "; ") + "stopped after file line " +
                   std::to_string(progress_.last_answered_line) + " was answered");
  } else {
    finish_job(JobOutcome::Error, "controller reset during the job after file line " +
                                      std::to_string(progress_.last_answered_line) +
                                      " was answered; machine position may be lost, re-home before restarting");
  }
}

void GrblSession::on_status(const StatusReport& raw) {
  const StatusReport r = tracker_.update(raw);
  Event e{EventKind::Status, r.state_text};
  e.status = r;
  emit(std::move(e));
  jog_.on_status(r, now_);
  if (is_active(progress_.state) && progress_.mode == JobMode::Run) {
    execution_.on_status(r.planner_free, r.state == MachineState::Idle, profile_.planner_blocks);
    progress_.executing_line = execution_.executing_line();
  }
  if (r.mpg) {
    if (*r.mpg && !mpg_owned_) emit({EventKind::Warning, "a pendant (MPG) owns the controller; sending paused"});
    if (!*r.mpg && mpg_owned_) emit({EventKind::Info, "MPG released; sending continues"});
    mpg_owned_ = *r.mpg;
  }
  if (r.state == MachineState::Tool && !tool_state_reported_) {
    tool_state_reported_ = true;
    emit({EventKind::Info, "tool change requested: change the tool, then acknowledge it (cycle start)"});
  } else if (r.state != MachineState::Tool) {
    tool_state_reported_ = false;
  }
  // A "Hold" without a sub-state (some forks) counts as stopped once two
  // reports in a row give the same machine position.
  const bool hold_unmoved = r.state == MachineState::Hold && r.substate < 0 && r.mpos && last_mpos_ &&
                            *r.mpos == *last_mpos_;
  last_mpos_ = r.mpos;
  idle_in_row_ = r.state == MachineState::Idle ? idle_in_row_ + 1 : 0;
  check_silence();
  if (draining_ && progress_.state == JobState::Running) {
    idle_reports_ = r.state == MachineState::Idle ? idle_reports_ + 1 : 0;
    if (idle_reports_ >= 2) {
      finish_job(JobOutcome::Completed, "all " + std::to_string(progress_.total_lines) +
                                            " lines answered and the machine is idle");
      return;
    }
  }
  if (stop_requested_ && !expect_reset_ && progress_.state == JobState::Stopping) {
    // Door:0 ready to resume, Door:1 stopped with the door ajar; 2 and 3 still move.
    const bool still = (r.state == MachineState::Hold && r.substate == 0) || hold_unmoved ||
                       r.state == MachineState::Idle || r.state == MachineState::Alarm ||
                       r.state == MachineState::Check || r.state == MachineState::Sleep ||
                       r.state == MachineState::Tool ||  // grblHAL's tool change: still, a hold is ignored there
                       (r.state == MachineState::Door && (r.substate == 0 || r.substate == 1));
    // Reset only once motion has stopped: a reset in motion raises ALARM:3
    // and loses the position; after Hold:0 it is clean.
    if (still) soft_reset();
  }
}

void GrblSession::check_silence() {
  if (silence_reported_ || !is_active(progress_.state) || expect_reset_ || idle_in_row_ < 2 ||
      in_flight_of(Origin::File) == 0)
    return;
  const PreparedLine& oldest = counter_.in_flight().front();
  // A dwell keeps GRBL idle and silent for its P seconds.
  double limit = kSilenceLimit;
  if (const auto g4 = oldest.text.find("G4"); g4 != std::string::npos) {
    if (const auto p = oldest.text.find('P', g4); p != std::string::npos) {
      double dwell = 0;
      const char* end = oldest.text.data() + oldest.text.size();
      if (std::from_chars(oldest.text.data() + p + 1, end, dwell).ec == std::errc() && std::isfinite(dwell) && dwell > 0)
        limit += dwell;
    }
  }
  if (now_ - waiting_since_ < limit) return;
  silence_reported_ = true;
  Event e{EventKind::Warning, "no answer to line " + std::to_string(oldest.source_line) + " '" + oldest.text +
                                  "' for " + fmt::format("{:.0f}", now_ - waiting_since_) +
                                  " s although the controller is idle: the line or its answer was lost on the wire "
                                  "(a dropped end of line never completes). The job cannot go on by itself: stop it "
                                  "and resume it from the journal."};
  e.source_line = oldest.source_line;
  e.line_text = oldest.text;
  emit(std::move(e));
}

void GrblSession::soft_reset() {
  write(std::string(1, static_cast<char>(profile_.realtime_byte(Realtime::SoftReset).value_or(0x18))));
  expect_reset_ = true;
  reset_deadline_ = now_ + kResetTimeout;
}

void GrblSession::pump() {
  // 0x85 goes out even behind a full receive buffer: it is a real-time byte.
  if (jog_.take_cancel() && !realtime(Realtime::JogCancel))
    emit({EventKind::Warning, "this controller has no jog-cancel byte; the queued jog moves will finish"});
  if (expect_reset_ || mpg_owned_) return;
  for (;;) {
    if (!commands_.empty()) {
      auto& [line, origin] = commands_.front();
      const bool may = origin == Origin::CheckToggle ||
                       (progress_.state != JobState::Running && progress_.state != JobState::Stopping);
      if (may) {
        if (!counter_.can_send(line)) return;
        if (counter_.in_flight_count() == 0) waiting_since_ = now_;
        write(counter_.send(line));
        in_flight_origin_.push_back(origin);
        commands_.pop_front();
        continue;
      }
    }
    if (progress_.state == JobState::Running &&
        (check_phase_ == CheckPhase::None || check_phase_ == CheckPhase::Streaming) &&
        next_index_ < program_.lines.size()) {
      const auto& line = program_.lines[next_index_];
      if (line.tool_change >= 0 && progress_.mode != JobMode::Check) {
        // A tool change: nothing more goes out until every line before it
        // is answered; then the session's routine takes over.
        if (in_flight_of(Origin::File) > 0) return;
        set_job_state(JobState::ToolChange, "tool change at file line " + std::to_string(line.source_line));
        return;
      }
      // Blank, or a tool change in a check pass (GRBL's $C would refuse M6).
      if (line.text.empty() || line.tool_change >= 0) {
        ++next_index_;
        ++progress_.lines_sent;
        ++progress_.lines_answered;  // nothing to answer: done once reached
        continue;
      }
      if (!counter_.can_send(line)) return;
      if (counter_.in_flight_count() == 0) waiting_since_ = now_;
      write(counter_.send(line));
      in_flight_origin_.push_back(Origin::File);
      ++next_index_;
      ++progress_.lines_sent;
      continue;
    }
    if ((!is_active(progress_.state) || progress_.state == JobState::ToolChange) && jog_.busy()) {
      // A jog line is at most ~60 bytes: ask the jog engine only when one fits,
      // so a move it hands out is always sent.
      PreparedLine room;
      room.text.assign(64, ' ');
      if (!counter_.can_send(room)) return;
      auto move = jog_.next_move(now_);
      if (!move) break;
      PreparedLine l;
      l.text = grbl_jog_line(move->delta, move->feed_mm_min);
      write(counter_.send(l));
      in_flight_origin_.push_back(Origin::Jog);
      continue;
    }
    break;
  }
  maybe_complete();
}

void GrblSession::start_job(PreparedProgram program, JobMode mode, double now) {
  now_ = now;
  if (is_active(progress_.state)) throw std::logic_error("a job is already running");
  if (!program.errors.empty()) {
    std::string all = "the program cannot be sent:";
    for (const auto& e : program.errors) all += "\n  " + e;
    throw std::invalid_argument(all);
  }
  for (const auto& l : program.lines)
    if (!l.text.empty() && CharacterCountingStream::cost(l) > counter_.capacity())
      throw std::invalid_argument("file line " + std::to_string(l.source_line) + " needs " +
                                  std::to_string(CharacterCountingStream::cost(l)) + " bytes but the controller's " +
                                  "receive buffer holds " + std::to_string(counter_.capacity()));
  jog_.cancel_all();
  pump_jog();
  program_ = std::move(program);
  next_index_ = 0;
  progress_ = JobProgress{};
  execution_.reset();
  run_after_check_ = mode == JobMode::CheckThenRun;
  if (mode == JobMode::CheckThenRun) mode = JobMode::Check;
  progress_.mode = mode;
  progress_.total_lines = program_.lines.size();
  error_seen_ = false;
  draining_ = false;
  stop_requested_ = false;
  abort_reason_.clear();
  modal_ = gcode::ParserState{};
  check_phase_ = CheckPhase::None;
  if (mode == JobMode::Check) {
    check_phase_ = CheckPhase::Entering;
    PreparedLine l;
    l.text = "$C";
    l.sync = true;
    commands_.emplace_front(std::move(l), Origin::CheckToggle);
  }
  set_job_state(JobState::Running, mode == JobMode::Check ? "check pass started" : "job started");
  pump();
}

void GrblSession::set_job_state(JobState s, const std::string& why) {
  progress_.state = s;
  emit({EventKind::JobState, std::string(to_string(s)) + ": " + why});
}

void GrblSession::finish_job(JobOutcome o, const std::string& text) {
  progress_.outcome = o;
  draining_ = false;
  if (o == JobOutcome::Completed) progress_.lines_answered = progress_.total_lines;
  // Completed: every line ran. Otherwise what ran is unknown past the
  // estimate (the planner was flushed), which stays as it was.
  if (o == JobOutcome::Completed || o == JobOutcome::CheckPassed || o == JobOutcome::CheckFailed) {
    execution_.all_done();
    progress_.executing_line = execution_.executing_line();
  }
  stop_requested_ = false;
  progress_.state = JobState::Finished;
  Event e{EventKind::JobFinished, std::string(to_string(o)) + ": " + text};
  e.source_line = progress_.last_answered_line;
  emit(std::move(e));
}

void GrblSession::pause() {
  if (progress_.state == JobState::ToolChange) {
    // The routine's motion holds; its state stays (it waits for Idle).
    write(std::string(1, static_cast<char>(profile_.realtime_byte(Realtime::FeedHold).value_or('!'))));
    return;
  }
  if (progress_.state != JobState::Running) return;
  write(std::string(1, static_cast<char>(profile_.realtime_byte(Realtime::FeedHold).value_or('!'))));
  hold_sent_ = true;
  set_job_state(JobState::Paused, "feed hold");
}

bool GrblSession::release_machine_hold() {
  // M0, a pendant or the door put the machine in Hold while the job runs:
  // resuming is cycle start then.
  const auto& st = tracker_.last();
  if (progress_.state != JobState::Running || !st || st->state != MachineState::Hold) return false;
  write(std::string(1, static_cast<char>(profile_.realtime_byte(Realtime::CycleStart).value_or('~'))));
  hold_sent_ = false;
  emit({EventKind::JobState, "cycle start: the machine was holding (program pause or pendant)"});
  return true;
}

void GrblSession::toggle_pause() {
  if (progress_.state == JobState::Paused || progress_.state == JobState::HeldOnError) return resume();
  if (progress_.state == JobState::ToolChange) {
    const auto& st = tracker_.last();
    if (st && (st->state == MachineState::Hold || st->state == MachineState::Door)) return resume();
    return pause();
  }
  // Space is cycle start for a machine holding by itself, not a second hold.
  if (release_machine_hold()) return;
  pause();
}

void GrblSession::resume() {
  if (progress_.state == JobState::ToolChange) {
    write(std::string(1, static_cast<char>(profile_.realtime_byte(Realtime::CycleStart).value_or('~'))));
    return;
  }
  if (release_machine_hold()) return;
  if (progress_.state != JobState::Paused && progress_.state != JobState::HeldOnError) return;
  write(std::string(1, static_cast<char>(profile_.realtime_byte(Realtime::CycleStart).value_or('~'))));
  hold_sent_ = false;
  set_job_state(JobState::Running, "resumed");
  pump();
}

void GrblSession::stop() {
  if (!is_active(progress_.state) || progress_.state == JobState::Stopping) return;
  stop_requested_ = true;
  set_job_state(JobState::Stopping, "holding, then resetting once motion has stopped");
  if (progress_.mode == JobMode::Check) {
    check_phase_ = CheckPhase::None;
    soft_reset();  // nothing moves in check mode
    return;
  }
  if (!hold_sent_) {
    write(std::string(1, static_cast<char>(profile_.realtime_byte(Realtime::FeedHold).value_or('!'))));
    hold_sent_ = true;
  }
  write(std::string(1, static_cast<char>(profile_.realtime_byte(Realtime::StatusReport).value_or('?'))));
}

void GrblSession::send_command(const std::string& line) {
  std::string err;
  auto cleaned = clean_gcode_line(line, {}, &err);
  if (!cleaned) throw std::invalid_argument("command '" + line + "': " + err);
  if (cleaned->empty()) return;
  if (cleaned->size() > profile_.line_length_limit)
    throw std::invalid_argument("command '" + line + "' is longer than " +
                                std::to_string(profile_.line_length_limit) + " characters");
  PreparedLine l;
  l.text = *cleaned;
  l.sync = is_persistent_write(l.text) || l.text.front() == '$';
  commands_.emplace_back(std::move(l), Origin::Command);
  pump();
}

std::optional<ProtocolEngine::ToolChangeStop> GrblSession::tool_change_stop() const {
  if (progress_.state != JobState::ToolChange || next_index_ >= program_.lines.size()) return std::nullopt;
  const auto& l = program_.lines[next_index_];
  return ToolChangeStop{l.source_line, l.tool_change};
}

void GrblSession::tool_change_done() {
  if (progress_.state != JobState::ToolChange) return;
  // The change's line counts as answered: it was carried out by the routine.
  progress_.last_answered_line = program_.lines[next_index_].source_line;
  ++next_index_;
  ++progress_.lines_sent;
  ++progress_.lines_answered;
  set_job_state(JobState::Running, "tool change done; the job goes on");
  pump();
}

void GrblSession::abort_job(const std::string& why) {
  if (!is_active(progress_.state)) return;
  abort_reason_ = why;
  error_seen_ = true;
  stop();
}

void GrblSession::disconnected() {
  counter_.clear();
  in_flight_origin_.clear();
  commands_.clear();
  jog_.forget();
  expect_reset_ = false;
  if (is_active(progress_.state))
    finish_job(JobOutcome::Disconnected, "controller disconnected; the last line it answered is file line " +
                                             std::to_string(progress_.last_answered_line) +
                                             ". Do not resume blindly: re-home and restart from a line.");
}

bool GrblSession::realtime(Realtime r) {
  const auto b = profile_.realtime_byte(r);
  if (!b) return false;
  write(std::string(1, static_cast<char>(*b)));
  return true;
}

double GrblSession::next_deadline() const {
  double t = opt_.poll_status ? next_poll_ : std::numeric_limits<double>::infinity();
  if (draining_ && progress_.state == JobState::Running && !expect_reset_) t = std::min(t, drain_poll_at_);
  if (expect_reset_) t = std::min(t, reset_deadline_);
  return std::min(t, jog_.next_deadline());
}

void GrblSession::pump_jog() {
  pump();
  emit_jog_notes();
}

}  // namespace cncstream::protocol
