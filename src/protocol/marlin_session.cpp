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

MarlinSession::MarlinSession(FirmwareProfile profile) : profile_(std::move(profile)) {
  if (profile_.flow != FlowControl::SendResponse)
    throw std::invalid_argument("MarlinSession needs a send-response profile, not '" + profile_.id + "'");
  for (const auto& l : profile_.startup_lines) {
    PreparedLine p;
    p.text = l;
    commands_.push_back(std::move(p));
  }
}

bool MarlinSession::busy() const {
  return !outstanding_.empty() || !commands_.empty() || !resend_queue_.empty() || is_active(progress_.state);
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
  pump();
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
    case ResponseKind::Busy: return;  // keepalive: last_rx_ already refreshed
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
    Event e{EventKind::LineAnswered, "ok"};
    e.source_line = s.line.source_line;
    e.line_text = s.line.text;
    emit(std::move(e));
  } else if (s.jog_segment) {
    if (jog_segments_queued_ > 0) --jog_segments_queued_;
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
    if (jog_dir_ && !is_active(progress_.state) && jog_segments_queued_ < 2) {
      PreparedLine l;
      // One segment covers 0.1 s at the jog feed, as GRBL's continuous jog does.
      l.text = "G1" + relative_move_words(*jog_dir_, jog_feed_ / 60.0 * 0.1, jog_feed_);
      const long n = next_n_;
      send_numbered(std::move(l), false);
      history_[n].jog_segment = true;
      outstanding_.back().jog_segment = true;
      ++jog_segments_queued_;
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
  if (jog_dir_) throw std::logic_error("a jog is running: release it first");
  if (mode != JobMode::Run) throw std::invalid_argument("Marlin has no check mode ($C)");
  if (!program.errors.empty()) {
    std::string all = "the program cannot be sent:";
    for (const auto& e : program.errors) all += "\n  " + e;
    throw std::invalid_argument(all);
  }
  program_ = std::move(program);
  next_index_ = 0;
  progress_ = JobProgress{};
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
  if (!outstanding_.empty() && !warned_silence_) return last_rx_ + profile_.busy_timeout_s;
  return std::numeric_limits<double>::infinity();
}

void MarlinSession::jog_step(const JogDirection& dir, double distance_mm, double feed_mm_min) {
  if (is_active(progress_.state)) throw std::logic_error("cannot jog while a job is running");
  for (std::string text : {std::string("G91"), "G1" + relative_move_words(dir, distance_mm, feed_mm_min),
                           std::string("G90")}) {
    PreparedLine l;
    l.text = std::move(text);
    commands_.push_back(std::move(l));
  }
  pump();
}

void MarlinSession::jog_start(const JogDirection& dir, double feed_mm_min) {
  if (is_active(progress_.state)) throw std::logic_error("cannot jog while a job is running");
  (void)relative_move_words(dir, 1.0, feed_mm_min);  // validates
  if (!jog_dir_) {
    PreparedLine l;
    l.text = "G91";
    commands_.push_back(std::move(l));
  }
  jog_dir_ = dir;
  jog_feed_ = feed_mm_min;
  pump();
}

void MarlinSession::jog_release() {
  if (!jog_dir_) return;
  jog_dir_.reset();
  // M410 discards every queued move at once; G90 restores absolute moves.
  PreparedLine stop, absolute;
  stop.text = "M410";
  absolute.text = "G90";
  commands_.push_front(std::move(absolute));
  commands_.push_front(std::move(stop));
  pump();
}

void MarlinSession::disconnected() {
  jog_dir_.reset();
  jog_segments_queued_ = 0;
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
  if (o == JobOutcome::Completed) progress_.lines_answered = progress_.total_lines;
  Event e{EventKind::JobFinished, std::string(to_string(o)) + ": " + text};
  e.source_line = progress_.last_answered_line;
  emit(std::move(e));
}

}  // namespace cncstream::protocol
