#pragma once
// What the WHB04B pendant does to one machine: key, knob and wheel events
// become session commands, and the LCD shows the machine. Lives on the
// session's io_context (the daemon owns one per pendant and names the
// machine it drives; `cncstream pendant PORT` owns one for a port); its input
// comes from a UsbPendantReader (a thread of its own that posts reports to
// that context) or a ReplayPlayer (an asio timer).
//
// Dead man: a continuous jog is started with a short lease that each wheel
// report renews; when the reports stop, the session cancels the jog itself.
// An unplugged receiver or a sleeping pendant cancels it at once.
//
// Threading: every method on the session's thread.
#include <boost/asio/steady_timer.hpp>

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "cncstream/pendant/whb04b_display.hpp"
#include "cncstream/pendant/whb04b_report.hpp"
#include "cncstream/session/machine_session.hpp"

namespace cncstream::pendant {

enum class LogLevel { Debug, Info, Warning };

// A macro's action: a built-in (a name starting with '@') or G-code lines
// separated by ';' sent as console lines (refused during a job, like any).
//   @zero-all           G10 L20 P0 X0 Y0 Z0 (work zero here)
//   @zero-selected      the axis on the axis knob only
//   @unlock             $X
//   @feed-100           feed override back to 100 %
//   @spindle-100        spindle override back to 100 %
//   @toggle-coordinates the LCD shows work <-> machine coordinates
struct PendantConfig {
  double lease_s = 0.2;               // a continuous jog ends this long after the last wheel report
  double display_interval_s = 0.2;    // the LCD is rewritten this often (as LinuxCNC does)
  double step_feed_mm_min = 0;        // step jogs' feed; 0: the machine's jog maximum
  bool work_coordinates = true;       // the LCD starts with work coordinates
  std::map<int, std::string> macros;  // macro number (1-16) -> action
};

// The macros a pendant has unless configured: Fn+Feed+ (1) @feed-100, Fn+Spindle+ (3) @spindle-100,
// Fn+W-Home (7) @zero-all, Macro-10 (10) @zero-selected, Fn+Reset (11) @unlock, Fn+Step (16) @toggle-coordinates.
std::map<int, std::string> default_macros();
// "N=ACTION" (N 1-16; an unknown @name is refused); throws std::invalid_argument naming the text.
std::pair<int, std::string> parse_macro_option(const std::string& text);

enum class JogMode { Step, Continuous };
const char* to_string(JogMode m);

class PendantController {
 public:
  PendantController(session::MachineSession& session, PendantConfig config);
  ~PendantController();
  PendantController(const PendantController&) = delete;
  PendantController& operator=(const PendantController&) = delete;

  // ---- input (the session's thread) --------------------------------------
  void connected();                             // the receiver is open: the LCD refresh starts
  void report(const InputReport& bytes);        // one input report
  void unplugged(const std::string& why);       // the receiver is gone: any jog stops now

  // ---- output ------------------------------------------------------------
  // Each LCD frame (the three feature reports) goes here while connected.
  void set_display_sink(std::function<void(const DisplayReports&)> sink) { display_sink_ = std::move(sink); }
  void set_log(std::function<void(LogLevel, const std::string&)> log) { log_ = std::move(log); }
  // Every input as it arrives (before it is decoded), to record a session
  // in the replay format: a report, an unplug or a (re)connection.
  enum class Input { Report, Unplug, Plug };
  void set_input_tap(std::function<void(Input, const InputReport&)> tap) { input_tap_ = std::move(tap); }
  // A line for the operator's log through the same sink (the reader's USB messages).
  void log(LogLevel level, const std::string& text);

  // ---- state -------------------------------------------------------------
  session::MachineSession& session() { return session_; }
  bool plugged() const { return plugged_; }
  bool sleeping() const { return tracker_.sleeping(); }
  JogMode mode() const { return mode_; }
  AxisKnob axis() const { return tracker_.axis(); }
  FeedKnob knob() const { return tracker_.knob(); }
  // What the LCD shows now (also what the next frame encodes).
  DisplayState display_state() const;
  struct Counters {
    std::size_t reports = 0, bad_reports = 0;
    // Detents moved, and detents not moved (clamped beyond the bound, or refused).
    std::size_t steps_sent = 0, steps_refused = 0;
    std::size_t continuous_starts = 0, renewals = 0, releases = 0;
    std::size_t frames = 0;
  };
  const Counters& counters() const { return counters_; }

 private:
  void on_event(const PendantEvent& e);
  void on_key(Key key, bool fn);
  void on_wheel(const PendantEvent& e);
  void run_macro(int number);
  void release_jog(const char* why, bool always = false);
  void send_owed_steps();
  void set_mode(JogMode m);
  void command(const char* what, const session::CommandResult& r);
  void arm_display();
  void refresh_display();
  bool spindle_running() const;

  session::MachineSession& session_;
  PendantConfig config_;
  PendantInputTracker tracker_;
  JogMode mode_ = JogMode::Step;  // a step per detent: the safer start
  bool plugged_ = false;
  bool work_coordinates_ = true;
  bool spindle_on_ = false;  // what we last asked for, when the controller does not say
  bool warned_rotary_ = false;
  // The continuous jog this pendant runs: axis and sign.
  std::optional<std::pair<int, int>> continuous_;
  // Step mode: detents turned and not yet sent as a jog (signed), on one
  // axis at one step size.
  static constexpr int kMaxOwedSteps = 10;
  struct OwedSteps {
    int axis = 0;
    double step_mm = 0;
    int steps = 0;
  };
  std::optional<OwedSteps> owed_;
  boost::asio::steady_timer display_timer_;
  std::function<void(const DisplayReports&)> display_sink_;
  std::function<void(LogLevel, const std::string&)> log_;
  std::function<void(Input, const InputReport&)> input_tap_;
  Counters counters_;
  std::shared_ptr<bool> alive_;
};

}  // namespace cncstream::pendant
