#include "cncstream/pendant/pendant_controller.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cncstream::pendant {

using protocol::JogDirection;
using protocol::Realtime;

namespace {

const char* const kBuiltins[] = {"@zero-all", "@zero-selected", "@unlock", "@feed-100", "@spindle-100",
                                 "@toggle-coordinates"};

bool is_builtin(const std::string& action) {
  return std::find(std::begin(kBuiltins), std::end(kBuiltins), action) != std::end(kBuiltins);
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  const auto e = s.find_last_not_of(" \t");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

const char kAxisLetters[] = "XYZ";

}  // namespace

std::map<int, std::string> default_macros() {
  return {{1, "@feed-100"}, {3, "@spindle-100"}, {7, "@zero-all"},
          {10, "@zero-selected"}, {11, "@unlock"}, {16, "@toggle-coordinates"}};
}

std::pair<int, std::string> parse_macro_option(const std::string& text) {
  const auto eq = text.find('=');
  int n = 0;
  std::size_t used = 0;
  if (eq != std::string::npos) {
    try {
      n = std::stoi(text.substr(0, eq), &used);
    } catch (const std::exception&) {
      used = 0;
    }
  }
  if (eq == std::string::npos || used != eq || n < 1 || n > 16)
    throw std::invalid_argument("macro '" + text + "': expected N=ACTION with N from 1 to 16 (e.g. 7=@zero-all)");
  std::string action = trim(text.substr(eq + 1));
  if (action.empty()) throw std::invalid_argument("macro '" + text + "': no action after '='");
  if (action[0] == '@' && !is_builtin(action)) {
    std::string known;
    for (const char* b : kBuiltins) known += std::string(known.empty() ? "" : ", ") + b;
    throw std::invalid_argument("macro '" + text + "': unknown built-in '" + action + "' (known: " + known + ")");
  }
  return {n, action};
}

const char* to_string(JogMode m) { return m == JogMode::Step ? "step" : "continuous"; }

PendantController::PendantController(session::MachineSession& session, PendantConfig config)
    : session_(session),
      config_(std::move(config)),
      work_coordinates_(config_.work_coordinates),
      display_timer_(session.executor()),
      alive_(std::make_shared<bool>(true)) {
  if (!(config_.lease_s > 0)) throw std::invalid_argument("pendant: the jog lease must be positive");
  if (!(config_.display_interval_s > 0)) throw std::invalid_argument("pendant: the display interval must be positive");
  for (const auto& [n, action] : config_.macros)
    if (n < 1 || n > 16 || action.empty() || (action[0] == '@' && !is_builtin(action)))
      throw std::invalid_argument("pendant: macro " + std::to_string(n) + " '" + action + "' is not a valid action");
}

PendantController::~PendantController() {
  *alive_ = false;
  // A jog must not outlive its holder: released first. A destructor that throws
  // ends the program (std::terminate); what may throw here (an allocation, a
  // timer's cancel) leaves nothing to undo, and a release that is lost still
  // ends at the jog's dead-man lease in the session.
  try {
    if (continuous_) session_.jog_release();
  } catch (...) {
  }
  try {
    display_timer_.cancel();
  } catch (...) {
  }
}

void PendantController::log(LogLevel level, const std::string& text) {
  if (log_) log_(level, text);
}

void PendantController::command(const char* what, const session::CommandResult& r) {
  if (r) log(LogLevel::Info, std::string("pendant: ") + what);
  else log(LogLevel::Warning, std::string("pendant: ") + what + " refused: " + r.reason);
}

// ---- input -----------------------------------------------------------------

void PendantController::connected() {
  if (input_tap_) input_tap_(Input::Plug, {});
  plugged_ = true;
  tracker_.reset();  // the knobs are unknown until the pendant reports them
  // A receiver that comes back starts in step mode, like a new one: the
  // operator sees STP on the LCD and no wheel turn runs away continuously.
  mode_ = JogMode::Step;
  log(LogLevel::Info, "pendant: receiver connected");
  refresh_display();
  arm_display();
}

void PendantController::unplugged(const std::string& why) {
  // First the machine, then the bookkeeping: this is the dead man.
  release_jog("the pendant's receiver is gone", true);
  if (input_tap_) input_tap_(Input::Unplug, {});
  plugged_ = false;
  owed_.reset();
  tracker_.reset();
  display_timer_.cancel();
  log(LogLevel::Warning, "pendant: receiver unplugged (" + why + ")");
}

void PendantController::report(const InputReport& bytes) {
  if (input_tap_) input_tap_(Input::Report, bytes);
  std::string why;
  const auto r = decode_report(bytes, &why);
  if (!r) {
    ++counters_.bad_reports;
    log(LogLevel::Warning, "pendant: ignored report " + hex_bytes(bytes.data(), bytes.size()) + ": " + why);
    return;
  }
  ++counters_.reports;
  if (!plugged_) plugged_ = true;  // a report proves it (e.g. a replay without a plug line)
  for (const auto& e : tracker_.update(*r)) on_event(e);
}

void PendantController::on_event(const PendantEvent& e) {
  switch (e.kind) {
    case PendantEventKind::Sleep:
      release_jog("the pendant went to sleep", true);
      log(LogLevel::Info, "pendant: asleep");
      return;
    case PendantEventKind::Wake: log(LogLevel::Info, "pendant: awake"); return;
    case PendantEventKind::AxisChanged:
      release_jog("the axis knob turned");
      log(LogLevel::Debug, std::string("pendant: axis ") + to_string(e.axis));
      refresh_display();  // the rows follow the knob (XYZ or ABC)
      return;
    case PendantEventKind::KnobChanged:
      release_jog("the feed knob turned");
      log(LogLevel::Debug, std::string("pendant: knob ") + to_string(e.knob));
      return;
    case PendantEventKind::KeyPressed: on_key(e.key, e.fn); return;
    case PendantEventKind::KeyReleased: return;  // every key acts on its press
    case PendantEventKind::Wheel: on_wheel(e); return;
  }
}

void PendantController::on_key(Key key, bool fn) {
  if (key == Key::Fn) return;  // a modifier only
  if (fn) {
    run_macro(fn_macro_number(key));
    return;
  }
  switch (key) {
    case Key::Reset: command("reset", session_.reset()); return;
    case Key::Stop:
      // The session's stop cancels every jog (held and queued steps) and stops a job.
      continuous_.reset();
      owed_.reset();
      command("stop", session_.stop());
      return;
    case Key::StartPause: {
      // At a tool change's prompt it is the operator's "continue": the tool
      // is mounted (or zeroed), or the measured length is right.
      if (session_.snapshot().tool_prompt) {
        command("tool change: continue", session_.tool_change_confirm());
        return;
      }
      // At the prompt of a routine outside a job (a tool routine, the corner
      // probe's question): the operator's confirm, as on the page.
      if (const auto* r = session_.routine(); r && r->pending_prompt()) {
        const std::string what = std::string(r->name()) + ": confirm";
        command(what.c_str(), session_.routine_confirm());
        return;
      }
      auto r = session_.toggle_hold();
      // No job: a hold from a feed hold key or a jog is resumed here too.
      const auto st = session_.status();
      if (!r && st && st->state == protocol::MachineState::Hold) r = session_.resume();
      command("start/pause", r);
      return;
    }
    case Key::FeedPlus: command("feed override +10 %", session_.realtime(Realtime::FeedOvPlus10)); return;
    case Key::FeedMinus: command("feed override -10 %", session_.realtime(Realtime::FeedOvMinus10)); return;
    case Key::SpindlePlus: command("spindle override +10 %", session_.realtime(Realtime::SpindleOvPlus10)); return;
    case Key::SpindleMinus: command("spindle override -10 %", session_.realtime(Realtime::SpindleOvMinus10)); return;
    case Key::MachineHome:
      release_jog("M-Home");
      command("home ($H)", session_.home());
      return;
    case Key::SafeZ:
      release_jog("Safe-Z");
      command("safe Z", session_.safe_z());
      return;
    case Key::WorkHome:
      release_jog("W-Home");
      command("go to work zero", session_.go_to_work_zero());
      return;
    case Key::SpindleOnOff: {
      const bool on = !spindle_running();
      const auto r = session_.spindle(on);
      if (r) spindle_on_ = on;
      command(on ? "spindle on" : "spindle off", r);
      return;
    }
    case Key::ProbeZ:
      release_jog("Probe-Z");
      command("probe Z", session_.probe_z());
      return;
    case Key::Continuous: set_mode(JogMode::Continuous); return;
    case Key::Step: set_mode(JogMode::Step); return;
    case Key::Macro10: run_macro(10); return;
    case Key::None:
    case Key::Fn: return;
  }
}

void PendantController::set_mode(JogMode m) {
  if (m == mode_) return;
  owed_.reset();
  release_jog("the jog mode changed");
  mode_ = m;
  log(LogLevel::Info, std::string("pendant: ") + to_string(m) + " mode");
  refresh_display();
}

void PendantController::run_macro(int number) {
  const auto it = config_.macros.find(number);
  if (it == config_.macros.end()) {
    log(LogLevel::Info, "pendant: macro " + std::to_string(number) + " has no action");
    return;
  }
  const std::string& action = it->second;
  const std::string what = "macro " + std::to_string(number) + " (" + action + ")";
  if (action == "@zero-all") {
    command(what.c_str(), session_.zero_axes("XYZ"));
  } else if (action == "@zero-selected") {
    const auto axis = axis_index(tracker_.axis());
    if (!axis) {
      log(LogLevel::Warning, "pendant: " + what + ": the axis knob is not on X, Y or Z");
      return;
    }
    command(what.c_str(), session_.zero_axes(std::string(1, kAxisLetters[*axis])));
  } else if (action == "@unlock") {
    command(what.c_str(), session_.unlock());
  } else if (action == "@feed-100") {
    command(what.c_str(), session_.realtime(Realtime::FeedOvReset));
  } else if (action == "@spindle-100") {
    command(what.c_str(), session_.realtime(Realtime::SpindleOvReset));
  } else if (action == "@toggle-coordinates") {
    work_coordinates_ = !work_coordinates_;
    log(LogLevel::Info, std::string("pendant: the display shows ") + (work_coordinates_ ? "work" : "machine") +
                            " coordinates");
    refresh_display();
  } else {
    release_jog("a macro");
    std::size_t start = 0;
    while (start <= action.size()) {
      const auto end = std::min(action.find(';', start), action.size());
      const std::string line = trim(action.substr(start, end - start));
      if (!line.empty()) {
        const auto r = session_.console(line);
        command((what + ": " + line).c_str(), r);
        if (!r) return;  // the rest of a macro makes no sense without its first lines
      }
      start = end + 1;
    }
  }
}

void PendantController::on_wheel(const PendantEvent& e) {
  const auto axis = axis_index(e.axis);
  if (!axis) {
    if (e.axis == AxisKnob::A || e.axis == AxisKnob::B || e.axis == AxisKnob::C) {
      if (!warned_rotary_) log(LogLevel::Warning, "pendant: this machine has X, Y and Z only: the wheel does nothing on A, B, C");
      warned_rotary_ = true;
    }
    return;  // off (or not reported yet): the wheel moves nothing
  }
  const int sign = e.detents > 0 ? 1 : -1;
  JogDirection dir;
  dir.v[static_cast<std::size_t>(*axis)] = sign;
  if (mode_ == JogMode::Step) {
    const auto step = knob_step_mm(e.knob);
    if (!step) {
      log(LogLevel::Debug, std::string("pendant: the knob is at ") + to_string(e.knob) + ": no step size in step mode");
      return;
    }
    // Every detent counts: the detents are added to what is owed on this
    // axis at this step size and go out as one jog when the session takes
    // one (at most two are queued; the rest waits, never dropped). A spin
    // beyond kMaxOwedSteps is clamped: motion must not run on long after the
    // wheel stops.
    if (owed_ && (owed_->axis != *axis || owed_->step_mm != *step)) {
      log(LogLevel::Info, fmt::format("pendant: {} owed step(s) on {} dropped: the axis or step size changed",
                                      std::abs(owed_->steps), kAxisLetters[owed_->axis]));
      owed_.reset();
    }
    if (!owed_) owed_ = OwedSteps{*axis, *step, 0};
    owed_->steps += e.detents;
    if (std::abs(owed_->steps) > kMaxOwedSteps) {
      const int over = std::abs(owed_->steps) - kMaxOwedSteps;
      owed_->steps = owed_->steps > 0 ? kMaxOwedSteps : -kMaxOwedSteps;
      counters_.steps_refused += static_cast<std::size_t>(over);
      log(LogLevel::Warning, fmt::format("pendant: wheel spun {} detent(s) beyond the {} a step jog may owe: clamped",
                                         over, kMaxOwedSteps));
    }
    send_owed_steps();
    return;
  }
  const auto percent = knob_percent(e.knob);
  if (!percent) {
    log(LogLevel::Debug, std::string("pendant: the knob is at ") + to_string(e.knob) + ": no continuous feed");
    return;
  }
  const std::pair<int, int> want{*axis, sign};
  if (continuous_ && *continuous_ != want) release_jog("the wheel turned the other way");
  // Faster turning, faster jog: four detents per report (about 10 per
  // second) and more is the knob's full percentage, a slow turn a quarter.
  const double speed = std::clamp(std::abs(e.detents) / 4.0, 0.25, 1.0);
  const double feed = session_.max_jog_feed() * *percent / 100.0 * speed;
  // The same direction again renews the lease and takes the new feed (the
  // session's jog_start does both); after the lease ran out it starts anew.
  const bool renewal = continuous_ == want;
  const auto r = session_.jog_start(dir, feed, config_.lease_s);
  if (!r) {
    continuous_.reset();
    log(LogLevel::Warning, "pendant: continuous jog refused: " + r.reason);
    return;
  }
  continuous_ = want;
  if (renewal) {
    ++counters_.renewals;
    return;
  }
  ++counters_.continuous_starts;
  log(LogLevel::Debug,
      fmt::format("pendant: continuous jog {}{} at {:.0f} mm/min", sign > 0 ? '+' : '-', kAxisLetters[*axis], feed));
}

void PendantController::send_owed_steps() {
  if (!owed_ || owed_->steps == 0) {
    owed_.reset();
    return;
  }
  JogDirection dir;
  dir.v[static_cast<std::size_t>(owed_->axis)] = owed_->steps > 0 ? 1 : -1;
  const double feed = config_.step_feed_mm_min > 0 ? config_.step_feed_mm_min : session_.max_jog_feed();
  const auto r = session_.jog_step(dir, std::abs(owed_->steps) * owed_->step_mm, feed);
  if (!r) {
    // Two steps in flight (or the machine busy): tried again at the next
    // report or display tick; a refusal that is no queue limit ends the debt.
    if (!session_.engine() || !session_.engine()->jogging() || mode_ != JogMode::Step) {
      counters_.steps_refused += static_cast<std::size_t>(std::abs(owed_->steps));
      log(LogLevel::Debug, "pendant: step refused: " + r.reason);
      owed_.reset();
    }
    return;
  }
  counters_.steps_sent += static_cast<std::size_t>(std::abs(owed_->steps));
  owed_.reset();
}

void PendantController::release_jog(const char* why, bool always) {
  const bool had = continuous_.has_value();
  continuous_.reset();
  const auto* engine = session_.engine();
  // The dead man (unplug, sleep) does not trust this bookkeeping: it always
  // cancels. (A release ends the held jog; the at most two queued steps run out.)
  if (!always && !had && !(engine && engine->jogging())) return;
  session_.jog_release();
  ++counters_.releases;
  log(LogLevel::Debug, std::string("pendant: jog released: ") + why);
}

bool PendantController::spindle_running() const {
  const auto st = session_.status();
  if (st && st->accessories) return st->accessories->find_first_of("SC") != std::string::npos;
  return spindle_on_;
}

// ---- display ---------------------------------------------------------------

DisplayState PendantController::display_state() const {
  DisplayState d;
  d.work_coordinates = work_coordinates_;
  d.mode = mode_ == JogMode::Step ? DisplayMode::Step : DisplayMode::Continuous;
  const auto snap = session_.snapshot();
  d.reset = snap.link != session::LinkState::Ready || snap.alarm;
  if (snap.status) {
    const auto& axes = work_coordinates_ ? snap.status->wpos : snap.status->mpos;
    // The -6 shows X Y Z, or A B C when its axis knob is on one of them.
    const auto a = tracker_.axis();
    const std::size_t first = (a == AxisKnob::A || a == AxisKnob::B || a == AxisKnob::C) ? 3 : 0;
    if (axes)
      for (std::size_t i = 0; i < 3; ++i)
        d.coordinates[i] = first + i < static_cast<std::size_t>(snap.status->axis_count) ? (*axes)[first + i] : 0.0;
  }
  if (snap.overrides) {
    d.feed = static_cast<unsigned>(std::max(0, (*snap.overrides)[0]));
    d.spindle = static_cast<unsigned>(std::max(0, (*snap.overrides)[2]));
  }
  return d;
}

void PendantController::refresh_display() {
  if (!plugged_ || !display_sink_) return;
  ++counters_.frames;
  display_sink_(encode_display_reports(display_state()));
}

void PendantController::arm_display() {
  display_timer_.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(config_.display_interval_s)));
  std::weak_ptr<bool> alive = alive_;
  display_timer_.async_wait([this, alive](const boost::system::error_code& ec) {
    if (ec || !alive.lock() || !plugged_) return;
    send_owed_steps();
    refresh_display();
    arm_display();
  });
}

}  // namespace cncstream::pendant
