#pragma once
// Keys from a terminal, as pure code: bytes and the time they arrived in,
// key events out (KeyDecoder); key events and time in, jog intents out
// (HeldKeyDetector). A terminal sends no key-up: a held key is a stream of
// auto-repeated presses, so "still held" is inferred from the repeats and
// "released" from their absence. No clocks or I/O here: the caller passes
// the time, so tests script both.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cncstream::app {

enum class Key {
  Char,      // a plain byte (letters, digits, space, control characters)
  Up,        // ESC [ A or ESC O A
  Down,      // ESC [ B / ESC O B
  Right,     // ESC [ C / ESC O C
  Left,      // ESC [ D / ESC O D
  PageUp,    // ESC [ 5 ~
  PageDown,  // ESC [ 6 ~
  Escape,    // a lone ESC (nothing followed it within the timeout)
  Unknown,   // any other or malformed escape sequence (function keys, modified arrows, Alt+key)
};
const char* to_string(Key k);

struct KeyEvent {
  Key key = Key::Char;
  char ch = 0;     // Key::Char only
  double at = 0;   // when its last byte arrived
  bool operator==(const KeyEvent&) const = default;
};

// Escape sequences: CSI (ESC [ params final) and SS3 (ESC O final). A lone
// ESC becomes Key::Escape once `esc_timeout_s` passes with nothing after it
// (terminals send a whole sequence in one write, so its bytes arrive
// together); an unfinished or over-long sequence becomes Key::Unknown, so
// garbage never swallows the keys after it.
class KeyDecoder {
 public:
  static constexpr double kDefaultEscTimeout_s = 0.05;
  static constexpr std::size_t kMaxSequence = 16;
  explicit KeyDecoder(double esc_timeout_s = kDefaultEscTimeout_s) : esc_timeout_s_(esc_timeout_s) {}

  // The keys completed by `bytes`, which arrived at `now`. A pending ESC
  // older than the timeout is resolved first.
  std::vector<KeyEvent> feed(std::string_view bytes, double now);
  // The key a pending ESC or unfinished sequence becomes when its timeout
  // has passed at `now` (call at deadline()).
  std::optional<KeyEvent> expire(double now);
  // When expire() has something to do; nullopt: nothing pending.
  std::optional<double> deadline() const;

 private:
  void push(char c, double now, std::vector<KeyEvent>& out);
  KeyEvent finish_csi(double now) const;
  double esc_timeout_s_;
  std::string seq_;  // the escape sequence read so far, ESC included ("" when none)
  double seq_at_ = 0;
};

// Which jog a key asks for: arrows X/Y, PgUp/PgDn Z.
enum class JogKey { None, XPlus, XMinus, YPlus, YMinus, ZPlus, ZMinus };
JogKey jog_key_of(const KeyEvent& k);
const char* to_string(JogKey k);

enum class JogIntentKind {
  Step,     // move one step of the current size
  Start,    // start a continuous jog (the key is held)
  Renew,    // the holder is alive: renew the continuous jog's lease
  Release,  // the key was let go (its repeats stopped) or another key came: stop the continuous jog
};
const char* to_string(JogIntentKind k);

struct JogIntent {
  JogIntentKind kind = JogIntentKind::Step;
  JogKey key = JogKey::None;
  bool operator==(const JogIntent&) const = default;
};

struct HeldKeyTiming {
  // The terminal's delay before the first repeat (X11 660 ms by default,
  // 200-600 ms elsewhere): a second press of the key within this is a
  // candidate repeat.
  double first_repeat_max_s = 0.7;
  // Repeats come every 25-50 ms on common terminals (X11 25/s, GNOME 30 ms,
  // macOS 83 ms at its default). A press this soon after a candidate
  // confirms the key is held; slower repeats cannot carry a lease short
  // enough to notice a release within 100 ms, so they stay steps.
  double repeat_period_max_s = 0.1;
  // Presses closer together than this came in one read (typed ahead, pasted,
  // or read late by a busy machine): they say nothing about auto-repeat.
  double min_repeat_period_s = 0.005;
  // The lease of a held key: lease_factor x the measured repeat period,
  // within [min_lease_s, max_lease_s]. max_lease_s bounds how long after
  // the last repeat the release is noticed.
  double lease_factor = 2.5;
  double min_lease_s = 0.06;
  double max_lease_s = 0.1;
};

// Jog keys + time -> intents. The first press of a jog key is a step. A
// second press of the same key within first_repeat_max_s is another step
// and a candidate repeat; a third within repeat_period_max_s of it confirms
// auto-repeat (a person cannot tap that fast) and starts a continuous jog.
// Why not start on the first repeat: a quick double tap looks the same and
// must stay two steps. Each further repeat renews the lease; silence past
// the lease (release), another key, or any non-jog key releases. After a
// lapse the key is a candidate again: a repeat within repeat_period_max_s
// (a late one on a busy machine) restarts the jog; a person cannot release
// and press again that fast.
class HeldKeyDetector {
 public:
  explicit HeldKeyDetector(HeldKeyTiming t = {}) : t_(t) {}

  // A key event. Non-jog keys release a held jog and are otherwise the
  // caller's business. The lease is checked first (as tick would).
  std::vector<JogIntent> on_key(const KeyEvent& k);
  // Releases a held key whose lease has run out at `now`.
  std::optional<JogIntent> tick(double now);
  // When tick() must run to notice a release; nullopt: no key held.
  std::optional<double> deadline() const;
  // Forget any held key without an intent (the caller stopped the jog itself:
  // quit, a lost connection, a refusal).
  void reset();

  bool holding() const { return state_ == State::Holding; }
  JogKey key() const { return key_; }
  double lease_s() const { return lease_s_; }
  double repeat_period_s() const { return period_s_; }

 private:
  enum class State { Idle, Tapped, Candidate, Holding };
  void set_lease(double interval);
  HeldKeyTiming t_;
  State state_ = State::Idle;
  JogKey key_ = JogKey::None;
  double last_ = 0;       // the key's last press
  double period_s_ = 0;   // measured repeat period (smoothed)
  double lease_s_ = 0;
};

}  // namespace cncstream::app
