// The simulated firmware: GRBL 1.1h's main loop, real-time commands, state
// machine and reports over the shared interpreter and motion planner.
#include "cncsim/machine.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>

#include "cncstream/gcode/arc_segments.hpp"
#include "cncstream/gcode/grbl_codes.hpp"

namespace cncsim {

using cncstream::geometry::Vec3;
namespace gc = cncstream::gcode;
namespace grbl = cncstream::grbl;

namespace {

constexpr double kMmPerInch = 25.4;
constexpr int kWcoRefreshBusy = 30, kWcoRefreshIdle = 10;
constexpr int kOvrRefreshBusy = 20, kOvrRefreshIdle = 10;
constexpr std::size_t kRxUsable = kRxBufferSize - 1;  // ring buffer keeps one slot free

bool is_realtime(unsigned char c) {
  return c == '?' || c == '!' || c == '~' || c == 0x18 || c >= 0x80;
}

}  // namespace

Machine::Machine(MachineOptions options)
    : options_(std::move(options)), queue_(cncstream::gcode::MotionLimits{}, options_.planner_blocks) {
  if (options_.store_path) store_ = load_store(*options_.store_path);
  queue_.set_limits(store_.settings.motion_limits());
  parser_.coords = store_.coords;
  parser_.coord_system = store_.coords.wcs[0];
  if (options_.probe_surface_z) {
    ProbeFace plane;
    plane.name = "probe plane";
    plane.everywhere = true;
    plane.top = *options_.probe_surface_z;
    probes_.add(plane);
  }
  for (const ProbeFace& f : options_.probe_faces) probes_.add(f);
  mounted_tool_ = options_.start_tool;
  if (options_.start_position) {
    queue_.set_position(*options_.start_position);
    parser_.position = *options_.start_position;
  }
  boot(true);
}

// ---- tools ------------------------------------------------------------------

double Machine::tip_drop() const {
  const auto& so = options_.stick_outs;
  const auto mounted = so.find(mounted_tool_), start = so.find(options_.start_tool);
  if (mounted == so.end() || start == so.end()) return 0;
  return mounted->second - start->second;
}

ProbeTool Machine::probe_tool() const {
  const auto it = options_.tool_shapes.find(mounted_tool_);
  if (it == options_.tool_shapes.end()) return std::nullopt;
  return it->second;
}

void Machine::apply_mount_request() {
  const int tool = mount_request_.tool.exchange(-1);
  if (tool >= 0) mount(tool);
}

void Machine::mount(int tool) {
  mounted_tool_ = tool;
  if (tool_observer_) tool_observer_(tool);
}

std::string link_summary(const LinkStats& s, double baud, std::size_t starved_below) {
  const std::string link = baud > 0 ? fmt::format("{:.0f} baud", baud) : std::string("unthrottled");
  const double share = s.commanded_feed() > 0 ? s.achieved_feed() / s.commanded_feed() * 100.0 : 0.0;
  return fmt::format(
      "link {}: starved {:.3f} s (planner below {} blocks with a line on its way), dry {:.3f} s; feed achieved "
      "{:.0f} of {:.0f} mm/min commanded ({:.1f} %) over {:.1f} mm of feed moves in {:.3f} s",
      link, s.starved_seconds, starved_below, s.dry_seconds, s.achieved_feed(), s.commanded_feed(), share, s.feed_mm,
      s.feed_seconds);
}

// ---- output -----------------------------------------------------------------

void Machine::emit(std::string_view line) {
  if (vanished_) return;
  out_.append(line);
  out_ += "\r\n";
}

void Machine::answer(int status) {
  if (vanished_) return;
  emit(status == 0 ? std::string("ok") : "error:" + std::to_string(status));
  ++lines_answered_;
  line_answered(status == 0);
  if (options_.faults.vanish_after && lines_answered_ >= options_.faults.vanish_after) {
    vanished_ = true;
    applied_.vanished = true;
  }
}

// ---- execution accounting ---------------------------------------------------

Machine::PendingLine* Machine::pending_line(std::size_t received) {
  for (auto it = pending_lines_.rbegin(); it != pending_lines_.rend(); ++it)
    if (it->received == received) return &*it;
  return nullptr;
}

void Machine::line_answered(bool ok) {
  // Lines are answered in the order they arrived: this answers the oldest unanswered one.
  const auto it = std::find_if(pending_lines_.begin(), pending_lines_.end(), [](const PendingLine& p) { return !p.answered; });
  if (it == pending_lines_.end()) return;
  if (ok) it->answered = true;
  else pending_lines_.erase(it);
  complete_lines();
}

void Machine::blocks_completed(std::size_t n) {
  for (; n > 0 && !planned_lines_.empty(); --n) {
    if (PendingLine* p = pending_line(planned_lines_.front()); p && p->blocks_left > 0) --p->blocks_left;
    planned_lines_.pop_front();
  }
  complete_lines();
}

void Machine::clear_planner() {
  for (std::size_t received : planned_lines_)
    std::erase_if(pending_lines_, [&](const PendingLine& p) { return p.received == received; });
  planned_lines_.clear();
  queue_.clear();
  complete_lines();
}

void Machine::forget_unanswered() {
  std::erase_if(pending_lines_, [](const PendingLine& p) { return !p.answered; });
  complete_lines();
}

void Machine::complete_lines() {
  while (!pending_lines_.empty() && pending_lines_.front().answered && pending_lines_.front().blocks_left == 0) {
    const PendingLine done = pending_lines_.front();
    pending_lines_.pop_front();
    if (!done.runs) continue;
    ++lines_executed_;
    if (line_observer_) line_observer_(ExecutedLine{done.received, done.n});
  }
}

std::string Machine::take_output() {
  std::string s;
  s.swap(out_);
  return s;
}

std::string Machine::format_vec(const Vec3& v) const {
  const bool inches = store_.settings.report_inches();
  const double k = inches ? 1.0 / kMmPerInch : 1.0;
  const double half_digit = inches ? 0.00005 : 0.0005;
  // The firmware never prints "-0.000": values that round to zero print as 0.
  auto clean = [&](double x) { return std::fabs(x * k) < half_digit ? 0.0 : x * k; };
  if (inches) return fmt::format("{:.4f},{:.4f},{:.4f}", clean(v.x), clean(v.y), clean(v.z));
  return fmt::format("{:.3f},{:.3f},{:.3f}", clean(v.x), clean(v.y), clean(v.z));
}

// ---- boot and reset -----------------------------------------------------------

void Machine::boot(bool power_on) {
  if (!vanished_) out_ += "\r\n";
  emit(kBanner);
  const bool locked = state_ == MachineState::Alarm || state_ == MachineState::Sleep ||
                      (power_on && store_.settings.homing());
  if (locked) {
    state_ = MachineState::Alarm;
    emit("[MSG:'$H'|'$X' to unlock]");
  } else {
    state_ = MachineState::Idle;
    run_startup_lines();
  }
}

void Machine::run_startup_lines() {
  for (const std::string& line : store_.startup_lines) {
    if (line.empty()) continue;
    const gc::BlockResult r = gc::execute_block(parser_, line);
    if (r.ok()) queue_actions(r);
    // The startup line's answer is part of its echo, not a line answer.
    steps_.push_back({});
    steps_.back().kind = Step::Emit;
    steps_.back().text = ">" + line + ":" + (r.ok() ? std::string("ok") : "error:" + std::to_string(r.status));
  }
  pump();
}

void Machine::soft_reset() {
  // GRBL's mc_reset() alarms in a cycle, homing, jog or while a hold is
  // still decelerating; a completed hold (Hold:0) clears EXECUTE_HOLD, so a
  // reset there keeps the position even with blocks left in the planner.
  const bool held = state_ == MachineState::Hold || state_ == MachineState::Door;
  const bool moving = (!queue_.empty() && !held) || state_ == MachineState::Home ||
                      state_ == MachineState::Run || state_ == MachineState::Jog ||
                      (held && !queue_.at_rest());
  if (moving && !critical_lock_) {
    const int code = state_ == MachineState::Home ? grbl::kAlarmHomingFailReset : grbl::kAlarmAbortCycle;
    state_ = MachineState::Alarm;
    emit("ALARM:" + std::to_string(code));
  }
  const Vec3 where = queue_.position();
  clear_planner();
  queue_.set_position(where);
  steps_.clear();
  forget_unanswered();
  rx_.clear();
  assembler_.reset();
  critical_lock_ = false;
  jog_cancel_ = false;
  paused_ = false;
  spindle_stop_ = false;
  feed_ovr_ = rapid_ovr_ = spindle_ovr_ = 100;
  apply_overrides();
  wco_counter_ = ovr_counter_ = 0;
  parser_ = gc::reset_parser(parser_);
  parser_.position = where;
  if (state_ != MachineState::Alarm && state_ != MachineState::Sleep) state_ = MachineState::Idle;
  boot(false);
}

// ---- input ----------------------------------------------------------------------

void Machine::receive(std::string_view bytes) {
  apply_mount_request();
  const double rate = options_.link_bytes_per_second;
  for (char ch : bytes) {
    if (vanished_) return;
    const auto c = static_cast<unsigned char>(ch);
    if (rate <= 0) {
      arrive(c);
      continue;
    }
    // The link is free again once its last byte has arrived.
    if (wire_.empty()) wire_next_ = now_ + 1.0 / rate;
    wire_.push_back(c);
  }
  deliver_due();
}

void Machine::deliver_due() {
  const double rate = options_.link_bytes_per_second;
  const bool instant = rate <= 0;  // the link was made unthrottled with bytes on it
  while (!wire_.empty() && !vanished_ && (instant || wire_next_ <= now_ + 1e-12)) {
    const unsigned char c = wire_.front();
    wire_.pop_front();
    if (!instant) wire_next_ += 1.0 / rate;
    arrive(c);
  }
  if (vanished_) wire_.clear();
}

// When the next byte that changes what the firmware does arrives: an end of
// line (the line can be parsed) or a real-time command; else the last byte.
double Machine::next_wire_event() const {
  const double gap = 1.0 / options_.link_bytes_per_second;
  const std::size_t scan = std::min<std::size_t>(wire_.size(), 512);
  for (std::size_t k = 0; k < scan; ++k) {
    const unsigned char c = wire_[k];
    if (c == '\n' || c == '\r' || is_realtime(c)) return wire_next_ + static_cast<double>(k) * gap;
  }
  return wire_next_ + static_cast<double>(scan - 1) * gap;
}

// The firmware has nothing to do but wait for a line that is on its way.
bool Machine::waiting_for_bytes() const {
  return steps_.empty() && (!wire_.empty() || !rx_.empty()) && !critical_lock_ && state_ != MachineState::Alarm &&
         state_ != MachineState::Hold && state_ != MachineState::Door;
}

void Machine::arrive(unsigned char c) {
  ++bytes_received_;
  ++link_stats_.bytes_arrived;
  Faults& f = options_.faults;
  // Real-time bytes are no part of a line: they move no line offset.
  const bool line_byte = !is_realtime(c);
  const bool eol = c == '\n' || c == '\r';
  bool drop = f.drop_every && bytes_received_ % f.drop_every == 0;
  bool corrupt = !drop && f.corrupt_every && bytes_received_ % f.corrupt_every == 0;
  if (line_byte && !drop && wire_fault(f.drop_byte_at, c, eol)) drop = true;
  if (line_byte && !drop && !corrupt && wire_fault(f.corrupt_byte_at, c, eol)) corrupt = true;
  if (line_byte) ++arriving_offset_;
  if (drop) {
    ++applied_.dropped_bytes;
    return;
  }
  if (corrupt) {
    unsigned char flipped = c ^ 0x01;
    if (is_realtime(flipped)) flipped = c ^ 0x02;
    c = flipped;
    ++applied_.corrupted_bytes;
  }
  if (line_byte && (c == '\n' || c == '\r')) {
    ++arriving_line_;
    arriving_offset_ = 0;
  }
  receive_byte(c);
}

bool Machine::wire_fault(std::map<std::size_t, ByteOfLine>& at, unsigned char c, bool eol) {
  const auto it = at.find(arriving_line_);
  if (it == at.end()) return false;
  const ByteOfLine& b = it->second;
  const bool hit = b.eol ? eol : b.letter ? c == static_cast<unsigned char>(b.letter) : arriving_offset_ == b.offset;
  if (!hit) return false;
  at.erase(it);  // once: a merged line keeps this line's number
  return true;
}

void Machine::receive_byte(unsigned char c) {
  if (is_realtime(c)) {
    realtime(c);
    return;
  }
  if (rx_.size() >= kRxUsable) {
    ++rx_dropped_;
    if (options_.strict) {
      throw RxOverflowError(fmt::format("RX buffer overflow: byte {} (0x{:02X}) from the host arrived while the {}-byte "
                                        "RX buffer was full and was dropped (line {}); the host must count characters",
                                        bytes_received_, c, kRxBufferSize, lines_received_ + 1));
    }
    return;
  }
  rx_.push_back(static_cast<char>(c));
  if (steps_.empty()) pump();
}

void Machine::realtime(unsigned char c) {
  switch (c) {
    case '?':
      out_ += status_report();
      out_ += "\r\n";
      break;
    case '!':
      feed_hold();
      break;
    case '~':
      cycle_start();
      break;
    case 0x18:
      soft_reset();
      break;
    case 0x84:  // safety door
      if (state_ == MachineState::Alarm || state_ == MachineState::Check || state_ == MachineState::Sleep) break;
      emit("[MSG:Check Door]");
      if (state_ == MachineState::Jog) {
        jog_cancel_ = true;
        queue_.hold();
        break;
      }
      if (!queue_.empty()) queue_.hold();
      state_ = MachineState::Door;
      break;
    case 0x85:  // jog cancel
      if (state_ == MachineState::Jog) {
        jog_cancel_ = true;
        queue_.hold();
      }
      break;
    case 0x90: feed_ovr_ = 100; apply_overrides(); break;
    case 0x91: feed_ovr_ = std::min(200, feed_ovr_ + 10); apply_overrides(); break;
    case 0x92: feed_ovr_ = std::max(10, feed_ovr_ - 10); apply_overrides(); break;
    case 0x93: feed_ovr_ = std::min(200, feed_ovr_ + 1); apply_overrides(); break;
    case 0x94: feed_ovr_ = std::max(10, feed_ovr_ - 1); apply_overrides(); break;
    case 0x95: rapid_ovr_ = 100; apply_overrides(); break;
    case 0x96: rapid_ovr_ = 50; apply_overrides(); break;
    case 0x97: rapid_ovr_ = 25; apply_overrides(); break;
    case 0x99: spindle_ovr_ = 100; ovr_counter_ = 0; break;
    case 0x9A: spindle_ovr_ = std::min(200, spindle_ovr_ + 10); ovr_counter_ = 0; break;
    case 0x9B: spindle_ovr_ = std::max(10, spindle_ovr_ - 10); ovr_counter_ = 0; break;
    case 0x9C: spindle_ovr_ = std::min(200, spindle_ovr_ + 1); ovr_counter_ = 0; break;
    case 0x9D: spindle_ovr_ = std::max(10, spindle_ovr_ - 1); ovr_counter_ = 0; break;
    case 0x9E:  // spindle stop toggles only in a completed hold
      if (state_ == MachineState::Hold && queue_.at_rest()) {
        spindle_stop_ = !spindle_stop_;
        ovr_counter_ = 0;
      }
      break;
    case 0xA0:
    case 0xA1:
      if (state_ == MachineState::Idle || state_ == MachineState::Run || state_ == MachineState::Hold) {
        if (c == 0xA0) parser_.modal.flood = !parser_.modal.flood;
        else parser_.modal.mist = !parser_.modal.mist;
        ovr_counter_ = 0;
      }
      break;
    default:
      break;  // other extended bytes are thrown away, as on the firmware
  }
}

void Machine::apply_overrides() {
  queue_.set_overrides(feed_ovr_ / 100.0, rapid_ovr_ / 100.0);
  ovr_counter_ = 0;
}

void Machine::feed_hold() {
  switch (state_) {
    case MachineState::Run:
      queue_.hold();
      state_ = MachineState::Hold;
      break;
    case MachineState::Idle:
      state_ = MachineState::Hold;
      queue_.hold();
      break;
    case MachineState::Jog:
      jog_cancel_ = true;  // a hold cancels a jog
      queue_.hold();
      break;
    default:
      break;
  }
}

void Machine::cycle_start() {
  if ((state_ == MachineState::Hold || state_ == MachineState::Door) && queue_.at_rest()) {
    paused_ = false;
    spindle_stop_ = false;
    queue_.resume();
    state_ = queue_.empty() ? MachineState::Idle : MachineState::Run;
    pump();
  } else if (state_ == MachineState::Idle && !queue_.empty()) {
    state_ = MachineState::Run;
  }
}

// ---- main loop ------------------------------------------------------------------

bool Machine::stalled() const { return !steps_.empty() && steps_.front().stall; }

bool Machine::busy() const {
  return !queue_.empty() || !steps_.empty() || !rx_.empty() || !wire_.empty();
}

void Machine::pump() {
  if (vanished_) return;
  for (;;) {
    if (critical_lock_) return;
    while (!steps_.empty()) {
      if (!run_front_step()) {
        if (options_.instant_waits) {
          const std::size_t before = steps_.size();
          const double t0 = now_;
          wait_instantly();
          if (steps_.size() == before && now_ == t0) return;
          if (critical_lock_) return;
          continue;
        }
        return;
      }
      if (!popped_) steps_.pop_front();
      popped_ = false;
      if (vanished_ || critical_lock_) return;
    }
    // The line buffer takes characters until an end of line.
    std::optional<gc::CleanLine> line;
    while (!rx_.empty() && !line) {
      const char c = rx_.front();
      rx_.pop_front();
      line = assembler_.push(c);
    }
    if (!line) return;
    process_line(*line);
  }
}

// Runs the oldest step of the current line; false when it must wait.
bool Machine::run_front_step() {
  Step& s = steps_.front();
  switch (s.kind) {
    case Step::Block:
      if (queue_.full()) return false;
      if (queue_.push(s.block)) {
        last_block_feed_ = !s.block.rapid;
        planned_lines_.push_back(s.block.tag);
        if (PendingLine* p = pending_line(s.block.tag)) ++p->blocks_left;
        if (s.jog && (state_ == MachineState::Idle || state_ == MachineState::Jog)) state_ = MachineState::Jog;
        else if (state_ == MachineState::Idle) state_ = MachineState::Run;
      }
      return true;
    case Step::Sync:
      return queue_.empty() && state_ != MachineState::Hold && state_ != MachineState::Door;
    case Step::Delay:
      if (!s.started) {
        s.started = true;
        s.until = now_ + s.seconds;
      }
      return now_ >= s.until - 1e-12;
    case Step::Homing:
      if (!s.started) {
        s.started = true;
        s.until = now_ + s.seconds;
        state_ = MachineState::Home;
      }
      if (now_ < s.until - 1e-12) return false;
      return run_and_pop(s);
    case Step::Pause:
      if (!s.started) {
        s.started = true;
        paused_ = true;
        state_ = MachineState::Hold;
        queue_.hold();
      }
      return !paused_;
    case Step::Emit:
      if (s.text.empty()) {
        answer(0);
      } else if (s.text.rfind("error:", 0) == 0 && s.text.size() > 6 && s.text[6] >= '0' && s.text[6] <= '9') {
        answer(std::stoi(s.text.substr(6)));
      } else {
        emit(s.text);
      }
      return true;
    case Step::Apply:
    case Step::ProbeEnd:
      return run_and_pop(s);
  }
  return true;
}

// An action may reset the machine (and so clear steps_): take it out and pop
// its step before running it. Returns true; popped_ tells pump() not to pop.
bool Machine::run_and_pop(Step& s) {
  std::function<void()> fn = std::move(s.apply);
  steps_.pop_front();
  popped_ = true;
  if (fn) fn();
  return true;
}

void Machine::wait_instantly() {
  // Let virtual time pass until the front step can go on.
  for (int guard = 0; guard < 1000000 && !steps_.empty() && !critical_lock_; ++guard) {
    Step& s = steps_.front();
    if (s.stall) return;
    if ((s.kind == Step::Delay || s.kind == Step::Homing) && s.started) {
      // Motion may still run during a delay (never in GRBL, which syncs first).
      if (s.until > now_) advance_motion(s.until - now_, false);
      now_ = std::max(now_, s.until);
      return;
    }
    if (!motion_can_run()) return;
    advance_motion(1e9, true);
    after_motion();
    if (s.kind == Step::Block && !queue_.full()) return;
    if (s.kind == Step::Sync && queue_.empty()) return;
  }
}

void Machine::process_line(const gc::CleanLine& line) {
  ++lines_received_;
  pending_lines_.push_back({lines_received_, 0, 0, false, state_ != MachineState::Check});
  const Faults& f = options_.faults;
  if (auto it = f.stall_at.find(lines_received_); it != f.stall_at.end()) {
    ++applied_.stalls;
    Step s;
    s.kind = Step::Delay;
    s.seconds = it->second;
    s.stall = true;  // a fault: never skipped, even at --speed max
    steps_.push_back(s);
  }
  if (auto it = f.alarm_at.find(lines_received_); it != f.alarm_at.end()) {
    ++applied_.alarms;
    if (it->second == grbl::kAlarmHardLimit || it->second == grbl::kAlarmSoftLimit) {
      raise_critical_alarm(it->second);
      return;  // the line is lost with the alarm; only a reset goes on
    }
    raise_alarm(it->second);
  }
  if (auto it = f.error_at.find(lines_received_); it != f.error_at.end()) {
    ++applied_.errors;
    steps_.push_back({Step::Emit, {}, 0, "error:" + std::to_string(it->second), {}, false, 0});
    return;
  }
  auto reply = [&](int status) {
    steps_.push_back({Step::Emit, {}, 0, status ? "error:" + std::to_string(status) : "", {}, false, 0});
  };
  if (line.overflow) return reply(grbl::kOverflow);
  if (line.text.empty()) return reply(0);
  if (line.text[0] == '$') return process_system(line.text);
  if (state_ == MachineState::Alarm || state_ == MachineState::Jog) return reply(grbl::kSystemGcLock);
  process_gcode(line.text);
}

void Machine::process_gcode(const std::string& text) {
  const gc::BlockResult r = gc::execute_block(parser_, text);
  if (!r.ok()) {
    steps_.push_back({Step::Emit, {}, 0, "error:" + std::to_string(r.status), {}, false, 0});
    return;
  }
  pending_lines_.back().n = r.state.line_number;
  queue_actions(r);
  if (critical_lock_) return;
  steps_.push_back({Step::Emit, {}, 0, "", {}, false, 0});
}

bool Machine::soft_limit_violated(const Vec3& t) const {
  if (!store_.settings.soft_limits()) return false;
  const Vec3 travel = store_.settings.max_travel();
  constexpr double eps = 1e-9;
  return t.x > eps || t.y > eps || t.z > eps || t.x < -travel.x - eps || t.y < -travel.y - eps ||
         t.z < -travel.z - eps;
}

void Machine::queue_actions(const gc::BlockResult& r) {
  const bool check = state_ == MachineState::Check;
  const int previous_tool = parser_.tool;
  parser_ = r.state;
  auto add_block = [&](const Vec3& from, const Vec3& to, double feed, bool rapid,
                       bool no_feed_override = false) -> bool {
    if (soft_limit_violated(to)) {
      raise_critical_alarm(grbl::kAlarmSoftLimit);
      return false;
    }
    if (check) return true;
    Step s;
    s.kind = Step::Block;
    s.block = {from, to, feed, rapid, parser_.line_number, lines_received_, no_feed_override};
    steps_.push_back(s);
    return true;
  };
  auto add_sync = [&] { if (!check) steps_.push_back({Step::Sync, {}, 0, {}, {}, false, 0}); };
  if (parser_.tool != previous_tool && !options_.operator_mounts_tools && !check) {
    add_sync();
    steps_.push_back({Step::Apply, {}, 0, {}, [this, t = parser_.tool] { mount(t); }, false, 0});
  }
  for (const gc::Action& a : r.actions) {
    if (const auto* m = std::get_if<gc::LinearMove>(&a)) {
      if (!add_block(m->from, m->to, m->feed, m->rapid)) return;
    } else if (const auto* arc = std::get_if<gc::ArcMove>(&a)) {
      const gc::ArcChords chords = gc::arc_chords(*arc, store_.settings.arc_tolerance());
      Vec3 p = arc->from;
      for (const Vec3& q : chords.points) {
        if (!add_block(p, q, chords.feed, false)) return;
        p = q;
      }
    } else if (const auto* pr = std::get_if<gc::ProbeMove>(&a)) {
      if (check) continue;
      add_sync();
      // GRBL 1.1's probe cycle with the TIP's geometry: the input must not
      // already be in the state sought (ALARM:4); the move stops where it
      // changes, the trigger position ([PRB]) is where it changed, and the
      // machine decelerates past it at the probe's feed (so the position
      // after a probe is never the trigger).
      const Vec3 drop{0, 0, tip_drop()};
      const ProbeTool tool = probe_tool();
      const bool active_at_start = probes_.triggered(pr->from - drop, tool);
      if (active_at_start == pr->toward) {
        steps_.push_back({Step::Apply, {}, 0, {}, [this] { raise_alarm(grbl::kAlarmProbeFailInitial); }, false, 0});
        return;
      }
      Vec3 stop = pr->to, trigger = pr->to;
      bool contact = false;
      if (const auto t = probes_.first_change(pr->from - drop, pr->to - drop, pr->toward, tool)) {
        const Vec3 d = pr->to - pr->from;
        trigger = pr->from + d * *t;
        const double length = norm(d);
        // Deceleration from the probe feed at the direction's acceleration.
        const Vec3 accel = store_.settings.motion_limits().acceleration;
        double a = 1e300;
        for (int i = 0; i < 3; ++i) {
          const double u = std::fabs((i == 0 ? d.x : i == 1 ? d.y : d.z) / length);
          const double ai = i == 0 ? accel.x : i == 1 ? accel.y : accel.z;
          if (u > 1e-12) a = std::min(a, ai / u);
        }
        const double v = std::min(pr->feed, 1e9) / 60.0;
        const double overshoot = std::min(v * v / (2 * a), length * (1 - *t));
        stop = trigger + d * (overshoot / length);
        contact = true;
      }
      if (!add_block(pr->from, stop, pr->feed, false, true)) return;
      add_sync();
      const bool error_on_fail = pr->error_on_fail;
      Step end;
      end.kind = Step::ProbeEnd;
      end.apply = [this, contact, error_on_fail, trigger] {
        probe_position_ = contact ? trigger : queue_.position();
        probe_succeeded_ = contact;
        parser_.position = queue_.position();
        if (!contact && error_on_fail) {
          raise_alarm(grbl::kAlarmProbeFailContact);
          return;
        }
        emit("[PRB:" + format_vec(probe_position_) + (contact ? ":1]" : ":0]"));
      };
      steps_.push_back(end);
    } else if (const auto* d = std::get_if<gc::Dwell>(&a)) {
      if (check) continue;
      add_sync();
      Step s;
      s.kind = Step::Delay;
      s.seconds = d->seconds;
      steps_.push_back(s);
    } else if (std::holds_alternative<gc::SpindleChange>(a) || std::holds_alternative<gc::CoolantChange>(a)) {
      add_sync();  // the firmware syncs the buffer before switching
    } else if (std::holds_alternative<gc::ProgramPause>(a)) {
      if (check) continue;
      add_sync();
      steps_.push_back({Step::Pause, {}, 0, {}, {}, false, 0});
    } else if (std::holds_alternative<gc::ProgramEnd>(a)) {
      add_sync();
      steps_.push_back({Step::Emit, {}, 0, "[MSG:Pgm End]", {}, false, 0});
    } else if (const auto* w = std::get_if<gc::CoordinateWrite>(&a)) {
      if (w->index < 6) store_.coords.wcs[static_cast<std::size_t>(w->index)] = w->value;
      else if (w->index == 6) store_.coords.g28 = w->value;
      else store_.coords.g30 = w->value;
      persist();
    } else if (std::holds_alternative<gc::WorkOffsetChange>(a)) {
      wco_counter_ = 0;
    }
  }
}

void Machine::raise_alarm(int code) {
  if (!queue_.empty()) {
    const Vec3 where = queue_.position();
    clear_planner();
    queue_.set_position(where);
    parser_.position = where;
  }
  state_ = MachineState::Alarm;
  emit("ALARM:" + std::to_string(code));
}

void Machine::raise_critical_alarm(int code) {
  // Hard limit: dead stop. Soft limit: the target was refused before moving
  // (the firmware holds first; any motion left is dropped with the alarm).
  const Vec3 where = queue_.position();
  clear_planner();
  queue_.set_position(where);
  parser_.position = where;
  steps_.clear();
  forget_unanswered();
  state_ = MachineState::Alarm;
  critical_lock_ = true;
  emit("ALARM:" + std::to_string(code));
  emit("[MSG:Reset to continue]");
}

void Machine::inject_hard_limit() {
  if (state_ == MachineState::Alarm && critical_lock_) return;
  raise_critical_alarm(grbl::kAlarmHardLimit);
}

void Machine::persist() {
  if (options_.store_path) save_store(*options_.store_path, store_);
}

// ---- '$' commands -----------------------------------------------------------------

void Machine::process_system(const std::string& line) {
  auto reply = [&](int status) {
    steps_.push_back({Step::Emit, {}, 0, status ? "error:" + std::to_string(status) : "", {}, false, 0});
  };
  auto say = [&](std::string text) { steps_.push_back({Step::Emit, {}, 0, std::move(text), {}, false, 0}); };
  const bool idle_or_alarm = state_ == MachineState::Idle || state_ == MachineState::Alarm;
  if (line.size() == 1) {
    say("[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]");
    return reply(0);
  }
  const char c1 = line[1];
  if (c1 == 'J') {
    if (state_ != MachineState::Idle && state_ != MachineState::Jog) return reply(grbl::kIdleError);
    if (line.size() < 3 || line[2] != '=') return reply(grbl::kInvalidStatement);
    const gc::BlockResult r = gc::execute_block(parser_, line, gc::BlockOptions{true});
    if (!r.ok()) return reply(r.status);
    const auto& jog = std::get<gc::JogMove>(r.actions.front());
    if (soft_limit_violated(jog.to)) return reply(grbl::kTravelExceeded);
    parser_.position = r.state.position;
    Step s;
    s.kind = Step::Block;
    s.block = {jog.from, jog.to, jog.feed, false, 0, lines_received_, true};
    s.jog = true;
    steps_.push_back(s);
    return reply(0);
  }
  if (c1 == '$' || c1 == 'G' || c1 == 'C' || c1 == 'X') {
    if (line.size() != 2) return reply(grbl::kInvalidStatement);
    if (c1 == '$') {
      if (state_ == MachineState::Run || state_ == MachineState::Hold) return reply(grbl::kIdleError);
      std::string report = store_.settings.report();
      report.resize(report.size() - 2);
      say(report);
    } else if (c1 == 'G') {
      say(gc::format_modes(parser_));
    } else if (c1 == 'C') {
      if (state_ == MachineState::Check) {
        say("[MSG:Disabled]");
        reply(0);
        Step s;
        s.kind = Step::Apply;
        s.apply = [this] { soft_reset(); };
        steps_.push_back(s);
        return;
      }
      if (state_ != MachineState::Idle) return reply(grbl::kIdleError);
      state_ = MachineState::Check;
      say("[MSG:Enabled]");
    } else if (state_ == MachineState::Alarm) {  // $X
      say("[MSG:Caution: Unlocked]");
      state_ = MachineState::Idle;
    }
    return reply(0);
  }
  if (!idle_or_alarm) return reply(grbl::kIdleError);
  switch (c1) {
    case '#': {
      if (line.size() != 2) return reply(grbl::kInvalidStatement);
      const char* names[] = {"G54", "G55", "G56", "G57", "G58", "G59"};
      for (std::size_t i = 0; i < 6; ++i) say(std::string("[") + names[i] + ":" + format_vec(parser_.coords.wcs[i]) + "]");
      say("[G28:" + format_vec(parser_.coords.g28) + "]");
      say("[G30:" + format_vec(parser_.coords.g30) + "]");
      say("[G92:" + format_vec(parser_.g92) + "]");
      say(fmt::format("[TLO:{:.3f}]", parser_.tool_length_offset));
      say("[PRB:" + format_vec(probe_position_) + (probe_succeeded_ ? ":1]" : ":0]"));
      return reply(0);
    }
    case 'H': {
      if (!store_.settings.homing()) return reply(grbl::kSettingDisabled);
      if (line.size() != 2) return reply(grbl::kInvalidStatement);
      start_homing();
      return;
    }
    case 'S':
      if (line != "$SLP") return reply(grbl::kInvalidStatement);
      say("[MSG:Sleeping]");
      reply(0);
      steps_.push_back({Step::Apply, {}, 0, {}, [this] { state_ = MachineState::Sleep; }, false, 0});
      return;
    case 'I':
      if (line.size() == 2) {
        say("[VER:1.1h.20190830:" + store_.build_info + "]");
        say("[OPT:VNM," + std::to_string(queue_.capacity()) + "," + std::to_string(kRxBufferSize) + "]");
        return reply(0);
      }
      if (line[2] != '=') return reply(grbl::kInvalidStatement);
      if (line.size() - 3 >= gc::kLineBufferSize - 1) return reply(grbl::kLineLengthExceeded);
      store_.build_info = line.substr(3);
      persist();
      return reply(0);
    case 'R': {
      if (line.size() != 6 || line.compare(0, 5, "$RST=") != 0) return reply(grbl::kInvalidStatement);
      const char what = line[5];
      if (what == '$' || what == '*') {
        store_.settings = Settings::defaults();
        queue_.set_limits(store_.settings.motion_limits());
      }
      if (what == '#' || what == '*') {
        store_.coords = {};
        parser_.coords = {};
      }
      if (what == '*') store_.startup_lines = {}, store_.build_info.clear();
      if (what != '$' && what != '#' && what != '*') return reply(grbl::kInvalidStatement);
      persist();
      say("[MSG:Restoring defaults]");
      reply(0);
      steps_.push_back({Step::Apply, {}, 0, {}, [this] { soft_reset(); }, false, 0});
      return;
    }
    case 'N':
      if (line.size() == 2) {
        say("$N0=" + store_.startup_lines[0]);
        say("$N1=" + store_.startup_lines[1]);
        return reply(0);
      }
      if (state_ != MachineState::Idle) return reply(grbl::kIdleError);
      [[fallthrough]];
    default: {
      std::size_t pos = c1 == 'N' ? 2 : 1;
      double parameter = 0;
      if (!gc::read_grbl_number(line, pos, parameter)) return reply(grbl::kBadNumberFormat);
      if (pos >= line.size() || line[pos] != '=') return reply(grbl::kInvalidStatement);
      ++pos;
      if (c1 == 'N') {
        const std::string block = line.substr(pos);
        const int n = static_cast<int>(parameter);
        if (n < 0 || n > 1) return reply(grbl::kInvalidStatement);
        // The firmware runs the block to validate it; errors are not stored.
        const gc::BlockResult r = gc::execute_block(parser_, block);
        if (!r.ok()) return reply(r.status);
        store_.startup_lines[static_cast<std::size_t>(n)] = block;
        persist();
        return reply(0);
      }
      double value = 0;
      if (!gc::read_grbl_number(line, pos, value)) return reply(grbl::kBadNumberFormat);
      if (pos != line.size() || parameter > 255) return reply(grbl::kInvalidStatement);
      const int status = store_.settings.set(static_cast<int>(parameter), value);
      if (status == 0) {
        queue_.set_limits(store_.settings.motion_limits());
        persist();
      }
      return reply(status);
    }
  }
}

void Machine::start_homing() {
  // Seek each cycle (Z, then X and Y) toward the switches at $25, locate at $24.
  const Settings& s = store_.settings;
  const Vec3 p = queue_.position();
  const double seek = std::max(1.0, s.get(25)) / 60.0, locate = std::max(1.0, s.get(24)) / 60.0;
  const double pulloff = s.get(27);
  const double seconds = std::fabs(p.z) / seek + std::max(std::fabs(p.x), std::fabs(p.y)) / seek +
                         4 * pulloff / locate;
  Step h;
  h.kind = Step::Homing;
  h.seconds = seconds;
  h.apply = [this, pulloff] {
    const int failure = options_.faults.homing_failure;
    if (failure) {
      state_ = MachineState::Alarm;
      emit("ALARM:" + std::to_string(failure));
      steps_.clear();
      answer(0);  // the firmware still answers $H before its reset banner
      forget_unanswered();
      state_ = MachineState::Alarm;
      const Vec3 where = queue_.position();
      clear_planner();
      queue_.set_position(where);
      rx_.clear();
      assembler_.reset();
      parser_ = gc::reset_parser(parser_);
      boot(false);
      return;
    }
    const Vec3 home{-pulloff, -pulloff, -pulloff};
    if (observer_) observer_(tip_position(), home - Vec3{0, 0, tip_drop()}, true);
    queue_.set_position(home);
    parser_.position = home;
    state_ = MachineState::Idle;
  };
  steps_.push_back(h);
  steps_.push_back({Step::Emit, {}, 0, "", {}, false, 0});
  Step startup;
  startup.kind = Step::Apply;
  startup.apply = [this] {
    if (state_ == MachineState::Idle) {
      // Startup lines run after a successful homing, after the $H 'ok'.
      for (const std::string& line : store_.startup_lines) {
        if (line.empty()) continue;
        const gc::BlockResult r = gc::execute_block(parser_, line);
        if (r.ok()) queue_actions(r);
        steps_.push_back({Step::Emit, {}, 0,
                          ">" + line + ":" + (r.ok() ? std::string("ok") : "error:" + std::to_string(r.status)),
                          {}, false, 0});
      }
    }
  };
  steps_.push_back(startup);
}

// ---- time ---------------------------------------------------------------------------

bool Machine::motion_can_run() const {
  if (queue_.empty() || critical_lock_) return false;
  return !(queue_.holding() && queue_.at_rest());
}

std::optional<double> Machine::next_timer() const {
  if (steps_.empty()) return std::nullopt;
  const Step& s = steps_.front();
  if ((s.kind == Step::Delay || s.kind == Step::Homing) && s.started) return s.until;
  return std::nullopt;
}

void Machine::advance_motion(double dt, bool stop_after_block) {
  // What cuts is the tip: the spindle's path less the mounted tool's extra length.
  const Vec3 drop{0, 0, tip_drop()};
  const auto traverse = [this, drop](const Vec3& a, const Vec3& b, const gc::MotionBlock& block) {
    if (observer_) observer_(a - drop, b - drop, block.rapid);
  };
  const auto r = queue_.advance(dt, observer_ ? gc::MotionQueue::Traverse(traverse) : gc::MotionQueue::Traverse{},
                                stop_after_block);
  now_ += r.time;
  link_stats_.feed_seconds += r.feed_time;
  link_stats_.feed_mm += r.feed_length;
  link_stats_.commanded_seconds += r.commanded_time;
  if (r.completed > 0) blocks_completed(r.completed);
}

void Machine::after_motion() {
  if (queue_.holding() && queue_.at_rest()) {
    if (jog_cancel_) {
      // Jog cancel: flush the planner and sync the parser to where we stopped.
      const Vec3 where = queue_.position();
      clear_planner();
      queue_.set_position(where);
      parser_.position = where;
      jog_cancel_ = false;
      if (state_ == MachineState::Jog) state_ = MachineState::Idle;
    }
  }
  if (queue_.empty()) {
    if (state_ == MachineState::Run) state_ = MachineState::Idle;
    if (state_ == MachineState::Jog) {
      state_ = MachineState::Idle;
      parser_.position = queue_.position();
    }
  }
}

void Machine::advance(double seconds) {
  apply_mount_request();
  const double end = now_ + seconds;
  const bool stalled_before = stalled();
  for (std::size_t guard = 0; guard < 100000000; ++guard) {
    deliver_due();
    pump();
    after_motion();
    // A stall fault that began with a line off the wire lasts wall-clock
    // time: hand back to the caller, which scales time by stalled().
    if (stalled() && !stalled_before) return;
    if (now_ >= end || vanished_) break;
    double slice = end - now_;
    if (auto t = next_timer()) slice = std::clamp(*t - now_, 0.0, slice);
    if (!wire_.empty()) slice = std::clamp(next_wire_event() - now_, 0.0, slice);
    const bool waiting_for_room = !steps_.empty() && steps_.front().kind == Step::Block;
    const bool waiting_for_sync = !steps_.empty() && steps_.front().kind == Step::Sync;
    // While a line is on its way, every block's end is a moment to count at.
    const bool starving = waiting_for_bytes();
    const double before = now_;
    if (motion_can_run()) {
      advance_motion(slice, waiting_for_room || waiting_for_sync || starving);
      if (now_ == before && slice > 0 && !motion_can_run()) now_ += slice;
    } else {
      now_ += slice;
    }
    if (starving) {
      // Blocks only leave the planner inside a slice and lines arrive at its
      // ends, so its depth at the end is the least it held.
      const double spent = now_ - before;
      if (queue_.size() < options_.starved_below_blocks) link_stats_.starved_seconds += spent;
      if (queue_.empty() && last_block_feed_) {
        link_stats_.dry_seconds += spent;
        link_stats_.feed_seconds += spent;
      }
    }
    after_motion();
  }
  if (now_ < end) now_ = end;
}

void Machine::run_until_idle(double max_seconds) {
  const double end = now_ + max_seconds;
  while (now_ < end && !vanished_) {
    pump();
    after_motion();
    if (queue_.empty() && steps_.empty() && rx_.empty() && wire_.empty()) break;
    if (!motion_can_run() && !next_timer() && wire_.empty()) {
      // Nothing will happen by itself (hold, alarm lock, M0): stop here.
      if (steps_.empty() || (steps_.front().kind != Step::Delay && steps_.front().kind != Step::Homing))
        break;
    }
    advance(std::min(1.0, end - now_));
  }
}

// ---- reports -------------------------------------------------------------------------

std::string Machine::state_name() const {
  switch (state_) {
    case MachineState::Idle: return "Idle";
    case MachineState::Run: return "Run";
    case MachineState::Hold: return queue_.at_rest() ? "Hold:0" : "Hold:1";
    case MachineState::Jog: return "Jog";
    case MachineState::Alarm: return "Alarm";
    case MachineState::Door: return queue_.at_rest() ? "Door:0" : "Door:2";
    case MachineState::Check: return "Check";
    case MachineState::Home: return "Home";
    case MachineState::Sleep: return "Sleep";
  }
  return "Idle";
}

std::string Machine::status_report() {
  const Settings& s = store_.settings;
  std::string r = "<" + state_name();
  const Vec3 mpos = queue_.position();
  if (s.report_machine_position()) {
    r += "|MPos:" + format_vec(mpos);
  } else {
    r += "|WPos:" + format_vec(mpos - parser_.wco());
  }
  if (s.report_buffer_state()) {
    r += "|Bf:" + std::to_string(queue_.capacity() - queue_.size()) + "," + std::to_string(kRxBufferSize - rx_.size());
  }
  if (const auto* b = queue_.current(); b && b->line_number > 0) r += "|Ln:" + std::to_string(b->line_number);
  {
    const double k = s.report_inches() ? 1.0 / kMmPerInch : 1.0;
    const bool spindle_on = parser_.modal.spindle != gc::SpindleState::Off && !spindle_stop_ &&
                            state_ != MachineState::Door && state_ != MachineState::Check;
    const double rpm = spindle_on ? parser_.spindle_speed * spindle_ovr_ / 100.0 : 0.0;
    r += fmt::format("|FS:{:.0f},{:.0f}", queue_.speed() * 60.0 * k, rpm);
  }
  if (probe_input()) r += "|Pn:P";
  const bool busy = state_ == MachineState::Run || state_ == MachineState::Hold || state_ == MachineState::Jog ||
                    state_ == MachineState::Home || state_ == MachineState::Door;
  if (wco_counter_ > 0) {
    --wco_counter_;
  } else {
    wco_counter_ = (busy ? kWcoRefreshBusy : kWcoRefreshIdle) - 1;
    if (ovr_counter_ == 0) ovr_counter_ = 1;  // Ov on the next report, never with WCO
    r += "|WCO:" + format_vec(parser_.wco());
  }
  {
    if (ovr_counter_ > 0) {
      --ovr_counter_;
    } else {
      ovr_counter_ = (busy ? kOvrRefreshBusy : kOvrRefreshIdle) - 1;
      r += "|Ov:" + std::to_string(feed_ovr_) + "," + std::to_string(rapid_ovr_) + "," + std::to_string(spindle_ovr_);
      std::string acc;
      if (parser_.modal.spindle == gc::SpindleState::CW && !spindle_stop_) acc += "S";
      if (parser_.modal.spindle == gc::SpindleState::CCW && !spindle_stop_) acc += "C";
      if (parser_.modal.flood) acc += "F";
      if (parser_.modal.mist) acc += "M";
      if (!acc.empty()) r += "|A:" + acc;
    }
  }
  return r + ">";
}

}  // namespace cncsim
