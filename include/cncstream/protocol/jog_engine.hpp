#pragma once
// The jog engine: which jog moves to send, and when, for step and continuous
// jogs. Pure: requests, answers, status reports and time in; moves, cancels
// and notes out. Each family engine (GRBL, Marlin) owns one and formats its
// moves ($J=G91... or G91 G1...).
//
// Continuous jogs follow GRBL's recipe (doc/markdown/jogging.md): short
// increments, each sent only after the previous one was answered, so at most
// one can reach the controller after a cancel (and a second cancel follows
// its answer). Increments are sized from the feed and the acceleration so
// the planner holds just the motion it needs to reach full speed, never more
// than a fraction of a second of it. A continuous jog needs a live holder:
// silence for its lease cancels it (the dead man no peer has).
#include <array>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "cncstream/protocol/grbl_settings.hpp"
#include "cncstream/protocol/jog.hpp"
#include "cncstream/protocol/status_report.hpp"

namespace cncstream::protocol {

struct JogLimits {
  std::array<double, 3> max_rate_mm_min{500, 500, 500};  // $110-$112
  std::array<double, 3> accel_mm_s2{10, 10, 10};          // $120-$122
  // Machine travel when soft limits are on ($20=1): GRBL keeps MPos within
  // [-$13x, 0] and answers error:15 to a jog beyond it.
  std::optional<std::array<double, 3>> travel_mm;
  double report_scale = 1.0;  // mm per reported unit (25.4 when $13=1)
};
// From a controller's `$$` (GRBL's shipped defaults where a value is missing).
JogLimits jog_limits_from(const GrblSettings& s);

struct JogConfig {
  int max_steps = 2;               // step jogs queued, in flight or moving at once
  int planner_blocks = 15;         // the controller's planner depth (GRBL: 15)
  double min_increment_s = 0.025;  // GRBL wants more than 10 ms per increment
  double min_queue_s = 0.1;        // motion kept ahead while held, at least
  double default_lease_s = 0.3;    // dead man: silence this long ends a continuous jog
  // A controller that reports no state (Marlin, not polled): a step counts
  // as finished once its motion time has passed, plus this margin.
  std::optional<double> settle_by_time_s;
};

struct JogMove {
  std::array<double, 3> delta{};  // mm, relative to where the previous move ends
  double feed_mm_min = 0;
  bool step = false;
};

class JogEngine {
 public:
  explicit JogEngine(JogConfig cfg = {}) : cfg_(cfg) {}
  void set_limits(const JogLimits& l) { limits_ = l; }
  const JogLimits& limits() const { return limits_; }
  const JogConfig& config() const { return cfg_; }

  // ---- requests: "" when accepted, else why not --------------------------
  std::string step(const JogDirection& dir, double distance_mm, double feed_mm_min, double now);
  // A continuous jog held for lease_s (<= 0: the default). The same direction
  // while held renews it and takes the new feed.
  std::string start(const JogDirection& dir, double feed_mm_min, double lease_s, double now);
  bool renew(double now);  // false when no continuous jog is held
  void release();          // the holder let go: cancel at once
  void cancel_all();       // a stop: queued steps dropped, moving jogs cancelled

  // ---- what the controller did -------------------------------------------
  // The oldest jog move in flight was answered (ok, or an error explained).
  void on_answer(bool ok, const std::string& error_text, double now);
  void on_status(const StatusReport& r, double now);
  // The controller says all jog motion has ended (GRBL: an Idle status
  // with nothing in flight; Marlin: its quick stop answered).
  void settled(double now);
  // Alarm, reset or a lost link: the controller dropped its jogs itself.
  void forget();

  void tick(double now);  // expires the lease
  double next_deadline() const;

  // ---- outputs -------------------------------------------------------------
  // The next move to send now, if one is due; the caller sends it as one
  // line and reports its answer through on_answer.
  std::optional<JogMove> next_move(double now);
  bool take_cancel();  // true once per cancel: send the jog cancel now
  std::vector<std::string> take_notes();

  // ---- state -----------------------------------------------------------------
  bool held() const { return held_.has_value(); }
  bool busy() const;  // anything queued, in flight, moving or being cancelled
  std::size_t in_flight() const { return in_flight_.size(); }
  int steps_outstanding() const;
  // The increment and the controller's stopping distance of the held jog (0: none).
  double increment_mm() const { return held_ ? held_->increment : 0; }
  double stop_distance_mm() const { return held_ ? held_->stop_distance : 0; }

 private:
  struct Held {
    std::array<double, 3> u{};  // unit direction
    double feed = 0, v = 0;     // mm/min and mm/s, within the axes' rates
    double increment = 0, queue = 0, stop_distance = 0;
    double lease_s = 0, lease_until = 0;
    double sent_mm = 0, first_sent_at = -1;
    std::optional<std::array<double, 3>> start_mpos;
    bool at_limit = false;
  };
  struct Moving {
    double done_at;  // when its motion time has passed (settle_by_time_s)
  };
  std::string refusal(double feed_mm_min) const;
  std::array<double, 3> unit(const JogDirection& dir) const;
  double rate_along(const std::array<double, 3>& u) const;
  double accel_along(const std::array<double, 3>& u) const;
  // Shortens `delta` to stay within travel from where the sent moves end;
  // returns the fraction kept (1: untouched).
  double clamp_to_travel(std::array<double, 3>& delta);
  double ahead_mm(double now) const;
  std::optional<std::array<double, 3>> mpos_mm() const;

  JogConfig cfg_;
  JogLimits limits_;
  std::optional<Held> held_;
  std::deque<JogMove> steps_;        // accepted, not sent
  std::deque<JogMove> in_flight_;    // sent, not answered
  std::vector<Moving> moving_;       // answered steps the machine may still run
  std::optional<StatusReport> status_;
  double status_at_ = 0;
  double last_now_ = 0;  // the latest time told
  std::optional<std::array<double, 3>> planned_end_;  // where the sent moves end (MPos, mm)
  bool cancel_ = false;
  int recancel_ = 0;          // answers still due from lines sent before a cancel
  bool winding_down_ = false;  // a cancel was sent: wait for Idle before new moves
  std::vector<std::string> notes_;
};

}  // namespace cncstream::protocol
