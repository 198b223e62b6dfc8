#include "jog_control.hpp"

#include <algorithm>
#include <cmath>

namespace cncstream::app {

namespace {

std::chrono::steady_clock::duration timer_duration(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
}

constexpr char kCtrlC = 0x03;
constexpr char kCtrlX = 0x18;

}  // namespace

double default_jog_feed(double max_jog_feed) { return max_jog_feed > 0 ? std::min(1000.0, max_jog_feed) : 1000.0; }

double next_jog_feed(double feed, int direction, double max_feed) {
  std::vector<double> ladder;
  for (double decade : {10.0, 100.0, 1e3, 1e4, 1e5})
    for (double m : {1.0, 2.0, 5.0}) ladder.push_back(m * decade);
  double next = feed;
  if (direction > 0) {
    const auto it = std::upper_bound(ladder.begin(), ladder.end(), feed * (1 + 1e-9));
    next = it == ladder.end() ? ladder.back() : *it;
  } else {
    const auto it = std::lower_bound(ladder.begin(), ladder.end(), feed * (1 - 1e-9));
    next = it == ladder.begin() ? ladder.front() : *std::prev(it);
  }
  if (max_feed > 0) next = std::min(next, max_feed);
  return std::max(next, 10.0);
}

JogControl::JogControl(session::MachineSession& session, JogControlOptions options)
    : session_(session),
      opt_(std::move(options)),
      detector_(opt_.timing),
      lease_timer_(session.executor()),
      esc_timer_(session.executor()),
      alive_(std::make_shared<bool>(true)) {
  if (opt_.steps_mm.empty()) throw std::invalid_argument("jog: no step sizes");
  opt_.step_index = std::min(opt_.step_index, opt_.steps_mm.size() - 1);
  if (opt_.feed_mm_min > 0) {
    feed_mm_min_ = opt_.feed_mm_min;
    feed_given_ = true;
  }
}

JogControl::~JogControl() {
  *alive_ = false;
  if (continuous_) session_.jog_release();
}

double JogControl::feed_cap() const { return session_.ready() ? session_.max_jog_feed() : 0; }

void JogControl::trace_line(const std::string& text) {
  opt_.trace(fmt::format("{:.4f} {}", trace_at_ >= 0 ? trace_at_ : session_.now(), text));
}

protocol::JogDirection JogControl::direction(JogKey k) const {
  switch (k) {
    case JogKey::XPlus: return {{1, 0, 0}};
    case JogKey::XMinus: return {{-1, 0, 0}};
    case JogKey::YPlus: return {{0, 1, 0}};
    case JogKey::YMinus: return {{0, -1, 0}};
    case JogKey::ZPlus: return {{0, 0, 1}};
    case JogKey::ZMinus: return {{0, 0, -1}};
    case JogKey::None: break;
  }
  return {};
}

void JogControl::show(std::string message) {
  message_ = std::move(message);
  if (on_change) on_change();
}

void JogControl::result(const session::CommandResult& r, const std::string& what) {
  trace("{}: {}", what, r ? "accepted" : r.reason.c_str());
  show(r ? what : "refused: " + r.reason);
}

void JogControl::on_bytes(std::string_view bytes) {
  const double now = session_.now();
  for (const KeyEvent& k : decoder_.feed(bytes, now)) handle_key(k);
  arm_timers();
}

void JogControl::handle_key(const KeyEvent& k) {
  const auto intents = detector_.on_key(k);
  for (const auto& i : intents) apply(i);
  if (opt_.trace) {  // after the commands: the key's own arrival time
    trace_at_ = k.at;
    if (k.key == Key::Char) trace("key 0x{:02x}", static_cast<unsigned char>(k.ch));
    else trace("key {}", to_string(k.key));
    trace_at_ = -1;
  }
  if (k.key == Key::Char) {
    handle_command_key(k.ch);
  } else if (k.key == Key::Escape) {
    if (intents.empty()) show("Esc: no jog held");
  } else if (k.key == Key::Unknown) {
    show("that key does nothing here (? lists the keys)");
  }
}

void JogControl::apply(const JogIntent& intent) {
  const char* key = to_string(intent.key);
  switch (intent.kind) {
    case JogIntentKind::Step: {
      const double step = opt_.steps_mm[opt_.step_index];
      const auto r = session_.jog_step(direction(intent.key), step, feed_mm_min_);
      result(r, std::string("step ") + key + " " + format_step(step) + " mm");
      break;
    }
    case JogIntentKind::Start: {
      // The session's own lease is a backstop (this class's lease, at most
      // HeldKeyTiming::max_lease_s, is the one that ends a released key).
      const auto r = session_.jog_start(direction(intent.key), feed_mm_min_, opt_.session_lease_s);
      continuous_ = r.accepted;
      trace("lease {:.3f} s (repeat period {:.3f} s)", detector_.lease_s(), detector_.repeat_period_s());
      result(r, std::string("jog ") + key + " held");
      break;
    }
    case JogIntentKind::Renew:
      if (continuous_) {
        if (const auto r = session_.jog_renew(); !r) {
          // The session ended it (soft limit, alarm, its lease): say so once;
          // the key's further repeats do nothing until it is let go.
          continuous_ = false;
          result(r, "renew");
        }
      }
      break;
    case JogIntentKind::Release:
      if (continuous_) {
        continuous_ = false;
        session_.jog_release();
        trace("release {}", key);
        show(std::string("jog ") + key + " released");
      }
      break;
  }
}

void JogControl::stop_jog(const std::string& why) {
  detector_.reset();
  lease_timer_.cancel();
  if (!continuous_) return;
  continuous_ = false;
  session_.jog_release();
  trace("release ({})", why);
  show("jog released: " + why);
}

void JogControl::handle_command_key(char c) {
  switch (c) {
    case '1': case '2': case '3': case '4': {
      const std::size_t i = static_cast<std::size_t>(c - '1');
      if (i >= opt_.steps_mm.size()) return show("no step size on that key");
      opt_.step_index = i;
      return show("step " + format_step(opt_.steps_mm[i]) + " mm");
    }
    case '+': case '=': case '-': {
      feed_mm_min_ = next_jog_feed(feed_mm_min_, c == '-' ? -1 : 1, feed_cap());
      feed_given_ = true;
      return show(fmt::format("jog feed {:.0f} mm/min", feed_mm_min_));
    }
    case '0': return result(session_.zero_axes("XYZ"), "work zero set at XYZ");
    case 'X': case 'Y': case 'Z': {
      const std::string axis(1, c);
      return result(session_.zero_axes(axis), "work zero set at " + axis);
    }
    case 'h': return result(session_.home(), "homing ($H)");
    case 'u': return result(session_.unlock(), "unlock ($X)");
    case 'p': return result(session_.probe_z(), "probing Z");
    case 'g': return result(session_.go_to_work_zero(), "going to work zero (safe Z first)");
    case 's': return result(session_.safe_z(), "up to safe Z");
    case ' ': case '!':
      // Jogging: cancel every jog, steps queued too (the session's stop).
      // Otherwise a feed hold (a go-to-work-zero move, a probe); ~ resumes.
      if (session_.snapshot().jogging) return result(session_.stop(), "jog cancelled");
      return result(session_.hold(), "feed hold (~ resumes)");
    case '~': return result(session_.resume(), "resume");
    case kCtrlX: return result(session_.reset(), "soft reset");
    case '?':
      if (on_print) on_print(jog_keys_help());
      return;
    case 'q': case kCtrlC:
      stop_jog("quit");
      quit_ = true;
      trace("quit");
      if (on_quit) on_quit();
      return;
    default: {
      if (static_cast<unsigned char>(c) >= 0x20 && c != 0x7f)
        return show(fmt::format("key '{}' does nothing here (? lists the keys)", c));
      return show(fmt::format("key 0x{:02x} does nothing here (? lists the keys)", static_cast<unsigned char>(c)));
    }
  }
}

void JogControl::arm_timers() {
  std::weak_ptr<bool> alive = alive_;
  if (const auto at = detector_.deadline()) {
    lease_timer_.expires_after(timer_duration(*at - session_.now()));
    lease_timer_.async_wait([this, alive](const boost::system::error_code& ec) {
      if (ec || !alive.lock()) return;
      if (auto r = detector_.tick(session_.now())) apply(*r);
      arm_timers();
    });
  } else {
    lease_timer_.cancel();
  }
  if (const auto at = decoder_.deadline()) {
    esc_timer_.expires_after(timer_duration(*at - session_.now()));
    esc_timer_.async_wait([this, alive](const boost::system::error_code& ec) {
      if (ec || !alive.lock()) return;
      if (auto k = decoder_.expire(session_.now())) handle_key(*k);
      arm_timers();
    });
  }
}

void JogControl::on_session_event(const session::SessionEvent& e) {
  using session::SessionEventKind;
  switch (e.kind) {
    case SessionEventKind::Link:
      if (e.link != session::LinkState::Ready) {
        // The session forgot the jog with the link; forget the key too, so
        // only fresh presses move the machine once it is back.
        if (continuous_) trace("link {}: jog ended", to_string(e.link));
        continuous_ = false;
        detector_.reset();
        lease_timer_.cancel();
      }
      if (!feed_given_ && e.link == session::LinkState::Ready) feed_mm_min_ = default_jog_feed(feed_cap());
      show(e.text);
      return;
    case SessionEventKind::Controller: {
      using protocol::EventKind;
      const auto& c = e.controller;
      switch (c.kind) {
        case EventKind::Status:
          if (on_change) on_change();
          return;
        case EventKind::Warning:
          // "jog refused: error:15 ..." (travel exceeded): the engine dropped the jog.
          if (c.text.rfind("jog refused", 0) == 0) continuous_ = false;
          return show(c.text);
        case EventKind::Alarm:
          if (continuous_) stop_jog(c.text);
          return show("ALARM: " + c.text);
        case EventKind::CommandAnswered:  // "$H: ok", "G10 ...: error:9 ..."
        case EventKind::Info:
        case EventKind::Reset:
          return show(c.text);
        default: return;
      }
    }
    default: return;
  }
}

DroView JogControl::view() const {
  DroView v;
  v.link = to_string(session_.link());
  if (const auto st = session_.status()) {
    v.state = st->state_text;
    v.wpos = st->wpos;
    v.mpos = st->mpos;
  }
  v.step_mm = opt_.steps_mm[opt_.step_index];
  v.feed_mm_min = feed_mm_min_;
  if (continuous_) v.jog = std::string(to_string(detector_.key())) + " held";
  v.message = message_;
  return v;
}

}  // namespace cncstream::app
