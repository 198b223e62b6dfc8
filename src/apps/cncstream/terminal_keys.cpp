#include "terminal_keys.hpp"

#include <algorithm>

namespace cncstream::app {

namespace {
constexpr char kEsc = 0x1b;
bool csi_param_or_intermediate(char c) { return c >= 0x20 && c <= 0x3f; }
bool final_byte(char c) { return c >= 0x40 && c <= 0x7e; }
}  // namespace

const char* to_string(Key k) {
  switch (k) {
    case Key::Char: return "char";
    case Key::Up: return "Up";
    case Key::Down: return "Down";
    case Key::Right: return "Right";
    case Key::Left: return "Left";
    case Key::PageUp: return "PgUp";
    case Key::PageDown: return "PgDn";
    case Key::Escape: return "Esc";
    case Key::Unknown: return "unknown key";
  }
  return "?";
}

std::vector<KeyEvent> KeyDecoder::feed(std::string_view bytes, double now) {
  std::vector<KeyEvent> out;
  if (auto k = expire(now)) out.push_back(*k);
  for (char c : bytes) push(c, now, out);
  return out;
}

void KeyDecoder::push(char c, double now, std::vector<KeyEvent>& out) {
  if (seq_.empty()) {
    if (c == kEsc) {
      seq_.push_back(c);
      seq_at_ = now;
    } else {
      out.push_back({Key::Char, c, now});
    }
    return;
  }
  const auto abandon = [&] {  // the sequence is garbage; `c` starts afresh
    out.push_back({Key::Unknown, 0, now});
    seq_.clear();
    push(c, now, out);
  };
  if (seq_.size() == 1) {  // ESC so far
    if (c == '[' || c == 'O') {
      seq_.push_back(c);
    } else if (c == kEsc) {  // the first ESC was a key of its own
      out.push_back({Key::Escape, 0, seq_at_});
      seq_at_ = now;
    } else if (static_cast<unsigned char>(c) >= 0x20) {  // Alt+key: not one of ours
      out.push_back({Key::Unknown, 0, now});
      seq_.clear();
    } else {
      out.push_back({Key::Escape, 0, seq_at_});
      seq_.clear();
      push(c, now, out);
    }
    return;
  }
  if (seq_[1] == 'O') {  // SS3: one final byte
    if (!final_byte(c)) return abandon();
    KeyEvent k{Key::Unknown, 0, now};
    switch (c) {
      case 'A': k.key = Key::Up; break;
      case 'B': k.key = Key::Down; break;
      case 'C': k.key = Key::Right; break;
      case 'D': k.key = Key::Left; break;
      default: break;
    }
    out.push_back(k);
    seq_.clear();
    return;
  }
  // CSI: parameters and intermediates, then one final byte.
  if (csi_param_or_intermediate(c)) {
    seq_.push_back(c);
    if (seq_.size() >= kMaxSequence) {
      out.push_back({Key::Unknown, 0, now});
      seq_.clear();
    }
    return;
  }
  if (!final_byte(c)) return abandon();
  seq_.push_back(c);
  out.push_back(finish_csi(now));
  seq_.clear();
}

KeyEvent KeyDecoder::finish_csi(double now) const {
  const std::string_view params = std::string_view(seq_).substr(2, seq_.size() - 3);
  const char fin = seq_.back();
  KeyEvent k{Key::Unknown, 0, now};
  // Modified arrows (ESC [ 1 ; 5 C) stay Unknown: a modifier is not a jog.
  if (params.empty() || params == "1") {
    switch (fin) {
      case 'A': k.key = Key::Up; break;
      case 'B': k.key = Key::Down; break;
      case 'C': k.key = Key::Right; break;
      case 'D': k.key = Key::Left; break;
      default: break;
    }
  } else if (fin == '~' && params == "5") {
    k.key = Key::PageUp;
  } else if (fin == '~' && params == "6") {
    k.key = Key::PageDown;
  }
  return k;
}

std::optional<KeyEvent> KeyDecoder::expire(double now) {
  if (seq_.empty() || now < seq_at_ + esc_timeout_s_) return std::nullopt;
  const KeyEvent k{seq_.size() == 1 ? Key::Escape : Key::Unknown, 0, seq_at_};
  seq_.clear();
  return k;
}

std::optional<double> KeyDecoder::deadline() const {
  if (seq_.empty()) return std::nullopt;
  return seq_at_ + esc_timeout_s_;
}

// ---- held keys ----------------------------------------------------------------

JogKey jog_key_of(const KeyEvent& k) {
  switch (k.key) {
    case Key::Right: return JogKey::XPlus;
    case Key::Left: return JogKey::XMinus;
    case Key::Up: return JogKey::YPlus;
    case Key::Down: return JogKey::YMinus;
    case Key::PageUp: return JogKey::ZPlus;
    case Key::PageDown: return JogKey::ZMinus;
    default: return JogKey::None;
  }
}

const char* to_string(JogKey k) {
  switch (k) {
    case JogKey::None: return "-";
    case JogKey::XPlus: return "X+";
    case JogKey::XMinus: return "X-";
    case JogKey::YPlus: return "Y+";
    case JogKey::YMinus: return "Y-";
    case JogKey::ZPlus: return "Z+";
    case JogKey::ZMinus: return "Z-";
  }
  return "?";
}

const char* to_string(JogIntentKind k) {
  switch (k) {
    case JogIntentKind::Step: return "step";
    case JogIntentKind::Start: return "start";
    case JogIntentKind::Renew: return "renew";
    case JogIntentKind::Release: return "release";
  }
  return "?";
}

void HeldKeyDetector::set_lease(double interval) {
  // Smoothed, so one late repeat (a busy machine) does not stretch the lease
  // and one early one does not cut it short.
  period_s_ = period_s_ > 0 ? 0.75 * period_s_ + 0.25 * interval : interval;
  lease_s_ = std::clamp(t_.lease_factor * period_s_, t_.min_lease_s, t_.max_lease_s);
}

std::optional<JogIntent> HeldKeyDetector::tick(double now) {
  if (state_ != State::Holding || now < last_ + lease_s_) return std::nullopt;
  // Still a candidate: the next repeat soon after restarts the jog (a late
  // repeat on a busy machine), a press later is a step.
  state_ = State::Candidate;
  return JogIntent{JogIntentKind::Release, key_};
}

std::optional<double> HeldKeyDetector::deadline() const {
  if (state_ != State::Holding) return std::nullopt;
  return last_ + lease_s_;
}

void HeldKeyDetector::reset() {
  state_ = State::Idle;
  key_ = JogKey::None;
  period_s_ = lease_s_ = 0;
}

std::vector<JogIntent> HeldKeyDetector::on_key(const KeyEvent& k) {
  std::vector<JogIntent> out;
  if (auto r = tick(k.at)) out.push_back(*r);
  const JogKey j = jog_key_of(k);
  if (j == JogKey::None) {
    if (state_ == State::Holding) out.push_back({JogIntentKind::Release, key_});
    reset();
    return out;
  }
  const double dt = k.at - last_;
  // Presses closer together than any repeat came in one read (typed ahead,
  // or read late): they say nothing about auto-repeat, each is a step.
  const bool repeat_like = dt >= t_.min_repeat_period_s;
  if (j == key_ && state_ != State::Idle) {
    if (state_ == State::Holding) {  // within the lease (tick above)
      if (repeat_like) set_lease(dt);
      last_ = k.at;
      out.push_back({JogIntentKind::Renew, j});
      return out;
    }
    if (state_ == State::Candidate && repeat_like && dt <= t_.repeat_period_max_s) {
      period_s_ = 0;  // measure afresh
      set_lease(dt);
      state_ = State::Holding;
      last_ = k.at;
      out.push_back({JogIntentKind::Start, j});
      return out;
    }
    state_ = repeat_like && dt <= t_.first_repeat_max_s ? State::Candidate : State::Tapped;
    last_ = k.at;
    out.push_back({JogIntentKind::Step, j});
    return out;
  }
  if (state_ == State::Holding) out.push_back({JogIntentKind::Release, key_});
  period_s_ = lease_s_ = 0;
  state_ = State::Tapped;
  key_ = j;
  last_ = k.at;
  out.push_back({JogIntentKind::Step, j});
  return out;
}

}  // namespace cncstream::app
