#include "cncstream/protocol/marlin_session.hpp"

#include <limits>
#include <stdexcept>

namespace cncstream::protocol {

namespace {

constexpr std::size_t kHistory = 64;  // Marlin only asks for recent lines

}  // namespace

int marlin_checksum(std::string_view s) {
  int cs = 0;
  for (unsigned char c : s) cs ^= c;
  return cs & 0xFF;
}

std::string marlin_frame(long n, std::string_view text) {
  std::string body;
  body.reserve(text.size() + 24);
  body.push_back('N');
  body.append(std::to_string(n));
  body.push_back(' ');
  body.append(text);
  const int cs = marlin_checksum(body);
  body.push_back('*');
  body.append(std::to_string(cs));
  return body;
}

namespace {
// Marlin is not polled for state: a jog step counts as done once its motion
// time has passed (plus this margin).
JogConfig marlin_jog_config() {
  JogConfig c;
  c.settle_by_time_s = 0.2;
  return c;
}
}  // namespace

MarlinSession::MarlinSession(FirmwareProfile profile)
    : ProtocolEngine(marlin_jog_config()), profile_(std::move(profile)) {
  // Marlin's settings are not read: cap jog feeds at a router's usual rates, and
  // size increments for a modest acceleration (M410 discards them anyway).
  JogLimits l;
  l.max_rate_mm_min = {3000, 3000, 600};  // an MPCNC-class router: a guess, said in docs/jogging.md
  l.accel_mm_s2 = {100, 100, 100};
  jog_.set_limits(l);
  if (profile_.flow != FlowControl::SendResponse)
    throw std::invalid_argument("MarlinSession needs a send-response profile, not '" + profile_.id + "'");
  for (const auto& l : profile_.startup_lines) {
    PreparedLine p;
    p.text = l;
    commands_.push_back(std::move(p));
  }
}

bool MarlinSession::busy() const {
  return !outstanding_.empty() || !commands_.empty() || !resend_queue_.empty() || is_active(progress_.state) ||
         jog_.busy() || !jog_lines_.empty();
}

void MarlinSession::on_bytes(std::string_view bytes, double now) {
  now_ = now;
  last_rx_ = now;
  warned_silence_ = false;
  splitter_.feed(bytes, [&](std::string_view line) { on_line(line, now); });
  pump();
}

void MarlinSession::tick(double now) {
  now_ = now;
  if (!outstanding_.empty() && !warned_silence_ && now - last_rx_ > profile_.busy_timeout_s) {
    warned_silence_ = true;
    emit({EventKind::Warning, "no answer from the controller for " + std::to_string(profile_.busy_timeout_s) +
                                  " s while line N" + std::to_string(outstanding_.front().n) + " is in flight"});
  }
  jog_.tick(now);
  pump_jog();
}

void MarlinSession::on_line(std::string_view line, double now) {
  now_ = now;
  last_rx_ = now;
  const Response r = parse_response(line);
  switch (r.kind) {
    case ResponseKind::Ok: on_ok(r); return;
    case ResponseKind::Resend: {
      if (r.code < 0) {
        emit({EventKind::Warning, r.parse_error});
        return;
      }
      const long from = r.code;
      // Lines before `from` were accepted; lines from `from` on go again, in order.
      while (!outstanding_.empty() && outstanding_.front().n < from) {
        Response fake;
        on_ok(fake);
      }
      if (from < next_n_ && !history_.count(from) && !(outstanding_.size() && outstanding_.front().n == from)) {
        finish_job(JobOutcome::Error, "controller asked to resend line N" + std::to_string(from) +
                                          ", which is no longer kept; stop and restart from a line");
        return;
      }
      resend_queue_.clear();
      for (long n = from; n < next_n_; ++n) {
        auto it = history_.find(n);
        if (it != history_.end()) resend_queue_.push_back(it->second);
      }
      outstanding_.clear();
      swallow_next_ok_ = true;
      ++resends_;
      emit({EventKind::Warning, "controller asked to resend from line N" + std::to_string(from)});
      return;
    }
    case ResponseKind::MarlinError: {
      const bool transmission = r.body.find("Last Line") != std::string::npos ||
                                r.body.find("checksum") != std::string::npos ||
                                r.body.find("Line Number") != std::string::npos;
      if (transmission) {
        emit({EventKind::Warning, "transmission error reported: " + r.body});
        return;
      }
      Event e{EventKind::Alarm, "controller error: " + r.body};
      e.source_line = progress_.last_answered_line;
      if (auto info = profile_.message_info(r.body)) {
        e.text += " (" + info->name + "): " + info->text + " What to do: " + info->action;
        e.info = std::move(info);
      } else {
        e.text += " (not in the " + profile_.id + " message table: see the firmware's documentation)";
      }
      emit(std::move(e));
      if (is_active(progress_.state))
        finish_job(JobOutcome::Error, "controller reported '" + r.body + "' after file line " +
                                          std::to_string(progress_.last_answered_line) + " was answered");
      return;
    }
    case ResponseKind::Busy:  // keepalive: last_rx_ already refreshed
    case ResponseKind::Empty: return;
    default: break;
  }
  if (r.line.rfind("start", 0) == 0 && !outstanding_.empty()) {
    emit({EventKind::Reset, "controller restarted"});
    outstanding_.clear();
    if (is_active(progress_.state))
      finish_job(JobOutcome::Error, "controller restarted during the job after file line " +
                                        std::to_string(progress_.last_answered_line) + " was answered");
    return;
  }
  emit({EventKind::Info, r.line});
}

void MarlinSession::on_ok(const Response& r) {
  if (r.ok_planner_free) planner_free_ = r.ok_planner_free;
  if (swallow_next_ok_) {
    swallow_next_ok_ = false;
    return;
  }
  if (counter_reset_sent_ && !counter_reset_acked_) {
    counter_reset_acked_ = true;
    return;
  }
  if (outstanding_.empty()) {
    emit({EventKind::Warning, "'ok' with no line in flight; ignored"});
    return;
  }
  Sent s = std::move(outstanding_.front());
  outstanding_.pop_front();
  if (s.file) {
    ++progress_.lines_answered;
    progress_.last_answered_line = s.line.source_line;
    apply_answered_line(modal_, s.line.text);
    // Marlin's `ok P<free>` (ADVANCED_OK) says how full the planner is;
    // without it the planner is taken to be full while the job streams.
    execution_.on_answered(s.line.source_line, s.line.text);
    execution_.on_status(r.ok_planner_free, false, profile_.planner_blocks);
    progress_.executing_line = execution_.executing_line();
    Event e{EventKind::LineAnswered, "ok"};
    e.source_line = s.line.source_line;
    e.line_text = s.line.text;
    emit(std::move(e));
  } else if (s.jog == JogRole::Move) {
    jog_.on_answer(true, {}, now_);
    emit_jog_notes();
  } else if (s.jog == JogRole::QuickStop) {
    jog_.settled(now_);
  } else if (s.jog == JogRole::Frame) {
  } else {
    Event e{EventKind::CommandAnswered, s.line.text + ": ok"};
    e.line_text = s.line.text;
    emit(std::move(e));
  }
  if (progress_.state == JobState::Stopping && outstanding_.empty()) quick_stop();
}

// Marlin has no feed hold: a stop sends M410 (quick stop), which the
// emergency parser acts on as the bytes arrive, discarding every queued move;
// without an emergency parser it runs once it reaches the queue's head.
void MarlinSession::quick_stop() {
  if (!quick_stop_sent_) {
    quick_stop_sent_ = true;
    PreparedLine l;
    l.text = "M410";
    send_numbered(std::move(l), false);
    return;
  }
  finish_job(JobOutcome::Stopped, "stopped after file line " + std::to_string(progress_.last_answered_line) +
                                      " was answered; M410 aborted the moves the controller had queued");
}

void MarlinSession::send_numbered(PreparedLine line, bool file) {
  const long n = next_n_++;
  write(marlin_frame(n, line.text) + "\n");
  Sent s{n, std::move(line), file};
  history_[n] = s;
  while (history_.size() > kHistory) history_.erase(history_.begin());
  outstanding_.push_back(std::move(s));
}

void MarlinSession::pump() {
  if (!counter_reset_sent_) {
    write("M110 N0\n");
    counter_reset_sent_ = true;
    next_n_ = 1;
    return;
  }
  if (!counter_reset_acked_ || swallow_next_ok_) return;
  const auto window = static_cast<std::size_t>(profile_.send_window);
  while (outstanding_.size() < window) {
    if (!resend_queue_.empty()) {
      Sent s = std::move(resend_queue_.front());
      resend_queue_.pop_front();
      write(marlin_frame(s.n, s.line.text) + "\n");
      outstanding_.push_back(std::move(s));
      continue;
    }
    if (!commands_.empty() && progress_.state != JobState::Running) {
      PreparedLine l = std::move(commands_.front());
      commands_.pop_front();
      send_numbered(std::move(l), false);
      continue;
    }
    // A jog move is three lines (Marlin acts on one G-code per line): G91,
    // the move, G90, so the modal state is absolute again whatever happens.
    if (!jog_lines_.empty()) {
      auto [text, role] = std::move(jog_lines_.front());
      jog_lines_.pop_front();
      send_jog_line(std::move(text), role);
      continue;
    }
    if (!is_active(progress_.state) && jog_.busy()) {
      auto move = jog_.next_move(now_);
      if (!move) break;
      jog_lines_.emplace_back("G91", JogRole::Frame);
      jog_lines_.emplace_back("G1" + move_words(move->delta, move->feed_mm_min), JogRole::Move);
      jog_lines_.emplace_back("G90", JogRole::Frame);
      continue;
    }
    if (progress_.state == JobState::Running && next_index_ < program_.lines.size()) {
      PreparedLine l = program_.lines[next_index_++];
      ++progress_.lines_sent;
      if (l.text.empty()) {
        ++progress_.lines_answered;
        continue;
      }
      send_numbered(std::move(l), true);
      continue;
    }
    break;
  }
  if (progress_.state == JobState::Running && next_index_ >= program_.lines.size() && outstanding_.empty() &&
      resend_queue_.empty())
    finish_job(JobOutcome::Completed, "all " + std::to_string(progress_.total_lines) + " lines answered");
}

void MarlinSession::start_job(PreparedProgram program, JobMode mode, double now) {
  now_ = now;
  if (is_active(progress_.state)) throw std::logic_error("a job is already running");
  if (jog_.busy()) throw std::logic_error("a jog is running: release it first");
  if (mode != JobMode::Run) throw std::invalid_argument("Marlin has no check mode ($C)");
  if (!program.errors.empty()) {
    std::string all = "the program cannot be sent:";
    for (const auto& e : program.errors) all += "\n  " + e;
    throw std::invalid_argument(all);
  }
  program_ = std::move(program);
  next_index_ = 0;
  progress_ = JobProgress{};
  execution_.reset();
  progress_.total_lines = program_.lines.size();
  progress_.state = JobState::Running;
  modal_ = gcode::ParserState{};
  emit({EventKind::JobState, "running: job started"});
  pump();
}

void MarlinSession::pause() {
  if (progress_.state != JobState::Running) return;
  progress_.state = JobState::Paused;
  emit({EventKind::JobState, "paused: feeding stopped; the controller finishes its queued moves"});
}

void MarlinSession::resume() {
  if (progress_.state != JobState::Paused) return;
  progress_.state = JobState::Running;
  emit({EventKind::JobState, "running: resumed"});
  pump();
}

void MarlinSession::stop() {
  if (!is_active(progress_.state) || progress_.state == JobState::Stopping) return;
  progress_.state = JobState::Stopping;
  resend_queue_.clear();
  quick_stop_sent_ = false;
  emit({EventKind::JobState, "stopping: no more file lines; M410 (quick stop) aborts the queued moves"});
  if (outstanding_.empty()) quick_stop();
}

void MarlinSession::send_command(const std::string& line) {
  CleanOptions opt;
  opt.strip_whitespace = false;
  opt.reject_realtime_chars = false;
  std::string err;
  auto cleaned = clean_gcode_line(line, opt, &err);
  if (!cleaned) throw std::invalid_argument("command '" + line + "': " + err);
  if (cleaned->empty()) return;
  PreparedLine l;
  l.text = *cleaned;
  commands_.push_back(std::move(l));
  pump();
}

bool MarlinSession::realtime(Realtime) { return false; }

double MarlinSession::next_deadline() const {
  double t = jog_.next_deadline();
  if (!outstanding_.empty() && !warned_silence_) t = std::min(t, last_rx_ + profile_.busy_timeout_s);
  return t;
}

void MarlinSession::send_jog_line(std::string text, JogRole role) {
  PreparedLine l;
  l.text = std::move(text);
  const long n = next_n_;
  send_numbered(std::move(l), false);
  history_[n].jog = role;
  outstanding_.back().jog = role;
}

void MarlinSession::pump_jog() {
  if (jog_.take_cancel()) {
    // M410 at once, past the window: the emergency parser acts on it as the
    // bytes arrive and discards every queued move; G90 follows in turn.
    jog_lines_.clear();  // moves not sent yet are simply dropped
    send_jog_line("M410", JogRole::QuickStop);
    PreparedLine absolute;
    absolute.text = "G90";
    commands_.push_front(std::move(absolute));
  }
  pump();
  emit_jog_notes();
}

void MarlinSession::disconnected() {
  jog_.forget();
  jog_lines_.clear();
  outstanding_.clear();
  resend_queue_.clear();
  commands_.clear();
  if (is_active(progress_.state))
    finish_job(JobOutcome::Disconnected, "controller disconnected; the last line it answered is file line " +
                                             std::to_string(progress_.last_answered_line));
}

void MarlinSession::finish_job(JobOutcome o, const std::string& text) {
  progress_.outcome = o;
  progress_.state = JobState::Finished;
  if (o == JobOutcome::Completed) {
    progress_.lines_answered = progress_.total_lines;
    execution_.all_done();
    progress_.executing_line = execution_.executing_line();
  }
  Event e{EventKind::JobFinished, std::string(to_string(o)) + ": " + text};
  e.source_line = progress_.last_answered_line;
  emit(std::move(e));
}

}  // namespace cncstream::protocol
