#pragma once
// The terminal jog mode's keys, driving one machine session: bytes from the
// terminal in (raw mode), session commands out, on the session's thread with
// no hop in between (a key reaches the port in the same call). Held keys are
// found from the terminal's auto-repeat (terminal_keys.hpp); a continuous jog
// lives only while its repeats keep coming: this class's lease timer releases
// it at most HeldKeyTiming::max_lease_s after the last repeat (each repeat
// also renews the session's own, longer lease: belt and braces), and a lost
// link, a quit, a signal or a closed stdin release it too (fail closed).
// Used by `cncstream jog`; the display (DRO) is the caller's.
#include <boost/asio/steady_timer.hpp>
#include <fmt/core.h>

#include <functional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "cncstream/protocol/jog.hpp"
#include "cncstream/session/machine_session.hpp"
#include "jog_display.hpp"
#include "terminal_keys.hpp"

namespace cncstream::app {

struct JogControlOptions {
  std::vector<double> steps_mm{0.01, 0.1, 1, 10};  // keys 1 2 3 4
  std::size_t step_index = 1;                      // 0.1 mm to start with
  double feed_mm_min = 0;                          // jog feed; 0: from the controller's rates (see default_feed)
  HeldKeyTiming timing;
  // The lease given to the session's continuous jog: a backstop should this
  // class's own lease (timing.max_lease_s at most, the one tested) not run.
  double session_lease_s = 0.3;
  // Called with each thing that happened, for --trace (null: nothing is
  // formatted). Written after the command went to the session, never before.
  std::function<void(const std::string&)> trace;
};

// The jog feed when none is given: 1000 mm/min, or the controller's
// maximum jog feed (MachineSession::max_jog_feed, $110-$112) when lower.
double default_jog_feed(double max_jog_feed);
// The next feed up (+1) or down (-1) on a 1-2-5 ladder, within [10, max].
double next_jog_feed(double feed, int direction, double max_feed);

class JogControl {
 public:
  JogControl(session::MachineSession& session, JogControlOptions options);
  ~JogControl();  // releases a held jog
  JogControl(const JogControl&) = delete;
  JogControl& operator=(const JogControl&) = delete;

  // Bytes read from the terminal just now.
  void on_bytes(std::string_view bytes);
  // Each session event (subscribe and forward): results, refusals,
  // alarms and the link; a lost link forgets the held key.
  void on_session_event(const session::SessionEvent& e);
  // Releases a held jog at once (quit, a signal, stdin closed).
  void stop_jog(const std::string& why);

  bool quit_requested() const { return quit_; }
  DroView view() const;

  std::function<void()> on_change;                      // something shown changed: redraw
  std::function<void(const std::string&)> on_print;     // a line for above the DRO (the key help)
  std::function<void()> on_quit;                        // q or Ctrl-C was pressed

 private:
  void handle_key(const KeyEvent& k);
  void apply(const JogIntent& intent);
  void handle_command_key(char c);
  void show(std::string message);
  void result(const session::CommandResult& r, const std::string& what);
  void arm_timers();
  // fmt checks the format against the arguments at compile time.
  template <typename... Args>
  void trace(fmt::format_string<Args...> format, Args&&... args) {
    if (opt_.trace) trace_line(fmt::format(format, std::forward<Args>(args)...));
  }
  void trace_line(const std::string& text);
  protocol::JogDirection direction(JogKey k) const;
  double feed_cap() const;  // 0 before the controller is ready

  session::MachineSession& session_;
  JogControlOptions opt_;
  KeyDecoder decoder_;
  HeldKeyDetector detector_;
  boost::asio::steady_timer lease_timer_, esc_timer_;
  double feed_mm_min_ = 500;
  bool feed_given_ = false;
  bool continuous_ = false;  // a continuous jog was accepted and not yet released
  bool quit_ = false;
  std::string message_;
  double trace_at_ = -1;  // the time of the next trace line (-1: now)
  std::shared_ptr<bool> alive_;
};

}  // namespace cncstream::app
