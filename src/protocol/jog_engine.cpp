#include "cncstream/protocol/jog_engine.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace cncstream::protocol {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr char kAxis[3] = {'X', 'Y', 'Z'};

double length(const std::array<double, 3>& d) { return std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]); }

std::string state_refusal(MachineState s) {
  switch (s) {
    case MachineState::Unknown:
    case MachineState::Idle:
    case MachineState::Jog:
    case MachineState::Tool: return {};  // grblHAL jogs in its tool-change state too
    case MachineState::Alarm: return "jog: the machine is in alarm; unlock or home it first";
    case MachineState::Check: return "jog: the controller is in check mode ($C); nothing would move";
    default: return std::string("jog: the machine is in ") + to_string(s) + "; jogs are accepted only when Idle";
  }
}

}  // namespace

JogLimits jog_limits_from(const GrblSettings& s) {
  JogLimits l;
  auto get = [&](int n) -> std::optional<double> {
    auto it = s.find(n);
    if (it == s.end() || !std::isfinite(it->second)) return std::nullopt;
    return it->second;
  };
  for (int i = 0; i < 3; ++i) {
    if (auto v = get(110 + i); v && *v > 0) l.max_rate_mm_min[i] = *v;
    if (auto v = get(120 + i); v && *v > 0) l.accel_mm_s2[i] = *v;
  }
  if (auto soft = get(20); soft && *soft != 0) {
    std::array<double, 3> t{};
    bool all = true;
    for (int i = 0; i < 3; ++i) {
      auto v = get(130 + i);
      if (!v || *v <= 0) all = false;
      else t[i] = *v;
    }
    if (all) l.travel_mm = t;
  }
  if (auto inches = get(13); inches && *inches != 0) l.report_scale = 25.4;
  return l;
}

std::array<double, 3> JogEngine::unit(const JogDirection& dir) const {
  const double n = length(dir.v);
  if (!(n > 0) || !std::isfinite(n)) return {};
  return {dir.v[0] / n, dir.v[1] / n, dir.v[2] / n};
}

// The planner limits a move's speed and acceleration so that no axis
// exceeds its own: along a diagonal the slowest axis (scaled) decides.
double JogEngine::rate_along(const std::array<double, 3>& u) const {
  double r = kInf;
  for (int i = 0; i < 3; ++i)
    if (std::fabs(u[i]) > 1e-9) r = std::min(r, limits_.max_rate_mm_min[i] / std::fabs(u[i]));
  return r;
}

double JogEngine::accel_along(const std::array<double, 3>& u) const {
  double a = kInf;
  for (int i = 0; i < 3; ++i)
    if (std::fabs(u[i]) > 1e-9) a = std::min(a, limits_.accel_mm_s2[i] / std::fabs(u[i]));
  return a;
}

std::string JogEngine::refusal(double feed) const {
  if (!(feed > 0) || !std::isfinite(feed)) return "jog: the feed must be a positive number of mm/min";
  if (status_) return state_refusal(status_->state);
  return {};
}

int JogEngine::steps_outstanding() const {
  int n = static_cast<int>(steps_.size() + moving_.size());
  for (const auto& m : in_flight_) n += m.step ? 1 : 0;
  return n;
}

bool JogEngine::busy() const {
  return held_ || !steps_.empty() || !in_flight_.empty() || !moving_.empty() || cancel_ || winding_down_;
}

std::string JogEngine::step(const JogDirection& dir, double distance_mm, double feed_mm_min, double) {
  const auto u = unit(dir);
  if (length(u) == 0) return "jog: the direction must be a non-zero vector";
  if (!(distance_mm > 0) || !std::isfinite(distance_mm)) return "jog: the step must be a positive distance";
  if (auto why = refusal(feed_mm_min); !why.empty()) return why;
  if (held_) return "jog: a continuous jog is running; release it first";
  if (winding_down_) return "jog: the last jog is still being cancelled";
  if (steps_outstanding() >= cfg_.max_steps)
    return "jog: " + std::to_string(cfg_.max_steps) + " steps are already queued; this one is dropped";
  JogMove m;
  m.step = true;
  m.feed_mm_min = std::min(feed_mm_min, rate_along(u));
  for (int i = 0; i < 3; ++i) m.delta[i] = u[i] * distance_mm;
  steps_.push_back(m);
  return {};
}

std::string JogEngine::start(const JogDirection& dir, double feed_mm_min, double lease_s, double now) {
  const auto u = unit(dir);
  if (length(u) == 0) return "jog: the direction must be a non-zero vector";
  if (auto why = refusal(feed_mm_min); !why.empty()) return why;
  if (lease_s <= 0) lease_s = cfg_.default_lease_s;
  if (held_) {
    const double same = held_->u[0] * u[0] + held_->u[1] * u[1] + held_->u[2] * u[2];
    if (same < 1 - 1e-9) return "jog: a continuous jog in another direction is running; release it first";
  }
  Held h = held_.value_or(Held{});
  h.u = u;
  h.feed = std::min(feed_mm_min, rate_along(u));
  h.v = h.feed / 60.0;
  const double a = accel_along(u);
  h.stop_distance = h.v * h.v / (2 * a);
  // Enough motion queued for the planner to reach full speed (it must be
  // able to stop within what it holds), spread over at most N-2 blocks, each
  // lasting at least min_increment_s.
  h.queue = std::max(1.25 * h.stop_distance, h.v * cfg_.min_queue_s);
  const int blocks = std::max(2, cfg_.planner_blocks - 2);
  h.increment = std::max(h.v * cfg_.min_increment_s, h.queue / blocks);
  h.lease_s = lease_s;
  h.lease_until = now + lease_s;
  last_now_ = now;
  steps_.clear();  // a held jog supersedes steps not sent yet
  held_ = h;
  return {};
}

bool JogEngine::renew(double now) {
  if (!held_) return false;
  held_->lease_until = now + held_->lease_s;
  return true;
}

void JogEngine::release() {
  if (!held_) return;
  const bool sent = held_->sent_mm > 0;
  held_.reset();
  if (!sent) return;
  cancel_ = true;
  winding_down_ = true;
  recancel_ = static_cast<int>(in_flight_.size());
}

void JogEngine::cancel_all() {
  const bool anything = held_ || !in_flight_.empty() || !moving_.empty();
  held_.reset();
  steps_.clear();
  if (!anything) return;
  cancel_ = true;
  winding_down_ = true;
  recancel_ = static_cast<int>(in_flight_.size());
}

void JogEngine::forget() {
  held_.reset();
  steps_.clear();
  in_flight_.clear();
  moving_.clear();
  cancel_ = false;
  recancel_ = 0;
  winding_down_ = false;
  planned_end_.reset();
}

void JogEngine::on_answer(bool ok, const std::string& error_text, double now) {
  last_now_ = now;
  if (in_flight_.empty()) return;
  const JogMove m = in_flight_.front();
  in_flight_.pop_front();
  if (recancel_ > 0) {
    --recancel_;
    // Sent before the cancel, parsed after it: it runs now, so cancel again.
    if (ok) cancel_ = true;
    return;
  }
  if (ok) {
    if (m.step) moving_.push_back({now + length(m.delta) / (m.feed_mm_min / 60.0)});
    return;
  }
  notes_.push_back("jog refused by the controller: " + error_text);
  planned_end_.reset();  // the move did not happen: learn the position again
  if (held_) {
    const bool moving = held_->sent_mm > 0;
    held_.reset();
    if (moving) {
      cancel_ = true;
      winding_down_ = true;
      recancel_ = static_cast<int>(in_flight_.size());
    }
  }
}

std::optional<std::array<double, 3>> JogEngine::mpos_mm() const {
  if (!status_ || !status_->mpos) return std::nullopt;
  const auto& p = *status_->mpos;
  const double k = limits_.report_scale;
  return std::array<double, 3>{p[0] * k, p[1] * k, p[2] * k};
}

void JogEngine::on_status(const StatusReport& r, double now) {
  last_now_ = now;
  status_ = r;
  status_at_ = now;
  if (r.state == MachineState::Alarm) {
    forget();
    return;
  }
  // Idle with nothing in flight: every answered step has ended (GRBL enters
  // Jog before it answers a jog line, so an Idle after the answer is the end).
  // grblHAL's Tool state is where a jog there ends.
  if ((r.state == MachineState::Idle || r.state == MachineState::Tool) && in_flight_.empty()) settled(now);
}

void JogEngine::settled(double now) {
  last_now_ = now;
  moving_.clear();
  if (winding_down_ && recancel_ == 0 && !cancel_) winding_down_ = false;
  if (!held_ && steps_.empty() && !winding_down_) planned_end_ = mpos_mm();
}

void JogEngine::tick(double now) {
  last_now_ = now;
  if (cfg_.settle_by_time_s)
    std::erase_if(moving_, [&](const Moving& m) { return m.done_at + *cfg_.settle_by_time_s <= now; });
  if (held_ && now >= held_->lease_until) {
    notes_.push_back(fmt::format("continuous jog cancelled: its holder was silent for {:.0f} ms (dead man)",
                                 held_->lease_s * 1000));
    release();
  }
}

double JogEngine::ahead_mm(double now) const {
  const Held& h = *held_;
  if (h.first_sent_at < 0) return 0;
  double travelled = h.v * std::max(0.0, now - h.first_sent_at);
  const auto p = mpos_mm();
  if (p && h.start_mpos && status_at_ > h.first_sent_at) {
    double along = 0;
    for (int i = 0; i < 3; ++i) along += ((*p)[i] - (*h.start_mpos)[i]) * h.u[i];
    if (status_->state == MachineState::Jog) along += h.v * (now - status_at_);
    travelled = along;
  }
  travelled = std::clamp(travelled, 0.0, h.sent_mm);
  return h.sent_mm - travelled;
}

double JogEngine::next_deadline() const {
  double t = kInf;
  if (cfg_.settle_by_time_s)
    for (const auto& m : moving_) t = std::min(t, m.done_at + *cfg_.settle_by_time_s);
  if (!held_) return t;
  t = std::min(t, held_->lease_until);
  if (in_flight_.empty() && !winding_down_ && !held_->at_limit && held_->first_sent_at >= 0) {
    // The queued motion runs down at the jog's speed: the next increment is
    // due when what is ahead falls to the target.
    const double over = ahead_mm(last_now_) - held_->queue;
    t = std::min(t, last_now_ + std::max(0.0, over) / held_->v + 1e-4);
  }
  return t;
}

double JogEngine::clamp_to_travel(std::array<double, 3>& delta) {
  if (!limits_.travel_mm || !planned_end_) return 1;
  double t = 1;
  for (int i = 0; i < 3; ++i) {
    const double lo = -(*limits_.travel_mm)[i], hi = 0, p = (*planned_end_)[i], d = delta[i];
    if (d > 0 && p + d > hi) t = std::min(t, std::max(0.0, (hi - p) / d));
    if (d < 0 && p + d < lo) t = std::min(t, std::max(0.0, (lo - p) / d));
  }
  for (auto& d : delta) d *= t;
  return t;
}

std::optional<JogMove> JogEngine::next_move(double now) {
  last_now_ = now;
  if (cancel_ || winding_down_) return std::nullopt;
  auto clamp_note = [&](const std::array<double, 3>& delta, const char* what) {
    std::string s = std::string("jog ") + what + " at the machine's travel ($130-$132, soft limits on):";
    for (int i = 0; i < 3; ++i)
      if (std::fabs(delta[i]) > 0 || (planned_end_ && std::fabs((*planned_end_)[i]) < 1e-9))
        s += fmt::format(" {} {:.3f}", kAxis[i], planned_end_ ? (*planned_end_)[i] + delta[i] : 0.0);
    notes_.push_back(std::move(s));
  };
  if (held_) {
    Held& h = *held_;
    if (h.at_limit || !in_flight_.empty()) return std::nullopt;
    if (h.first_sent_at >= 0 && ahead_mm(now) >= h.queue) return std::nullopt;
    JogMove m;
    m.feed_mm_min = h.feed;
    for (int i = 0; i < 3; ++i) m.delta[i] = h.u[i] * h.increment;
    const double kept = clamp_to_travel(m.delta);
    if (kept < 1) {
      h.at_limit = true;
      clamp_note(m.delta, "stopped");
      if (length(m.delta) < 0.001) return std::nullopt;
    }
    if (h.first_sent_at < 0) {
      h.first_sent_at = now;
      h.start_mpos = planned_end_;
    }
    h.sent_mm += length(m.delta);
    if (planned_end_)
      for (int i = 0; i < 3; ++i) (*planned_end_)[i] += m.delta[i];
    in_flight_.push_back(m);
    return m;
  }
  while (!steps_.empty()) {
    JogMove m = steps_.front();
    steps_.pop_front();
    const double kept = clamp_to_travel(m.delta);
    if (kept < 1) clamp_note(m.delta, length(m.delta) < 0.001 ? "step dropped" : "step shortened");
    if (length(m.delta) < 0.001) continue;
    if (planned_end_)
      for (int i = 0; i < 3; ++i) (*planned_end_)[i] += m.delta[i];
    in_flight_.push_back(m);
    return m;
  }
  return std::nullopt;
}

bool JogEngine::take_cancel() { return std::exchange(cancel_, false); }

std::vector<std::string> JogEngine::take_notes() { return std::exchange(notes_, {}); }

}  // namespace cncstream::protocol
