#include "cncstream/gcode/motion_planner.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cncstream::gcode {
namespace {

constexpr double kHuge = 1e30;
constexpr double kMinLength = 1e-9;


// Largest value along `unit` that keeps every axis within its own limit.
double limit_by_axes(const geometry::Vec3& per_axis, const geometry::Vec3& unit) {
  double limit = kHuge;
  for (int i = 0; i < 3; ++i) {
    const double u = std::fabs(component(unit, i));
    if (u > 1e-12) limit = std::min(limit, component(per_axis, i) / u);
  }
  return limit;
}

}  // namespace

MotionQueue::MotionQueue(const MotionLimits& limits, std::size_t capacity)
    : limits_(limits), capacity_(capacity) {}

void MotionQueue::set_limits(const MotionLimits& limits) { limits_ = limits; }

void MotionQueue::set_position(const geometry::Vec3& p) { position_ = p; }

double MotionQueue::nominal(const Planned& b) const {
  if (b.src.rapid) return b.rapid_rate * rapid_override_;
  return std::min(b.src.feed / 60.0 * (b.src.no_feed_override ? 1.0 : feed_override_), b.rapid_rate);
}

bool MotionQueue::push(const MotionBlock& block) {
  const geometry::Vec3 start = blocks_.empty() ? position_ : blocks_.back().src.to;
  const geometry::Vec3 delta = block.to - start;
  const double length = norm(delta);
  if (length < kMinLength) return false;
  Planned p;
  p.src = block;
  p.src.from = start;
  p.length = p.remaining = length;
  p.unit = delta / length;
  p.accel = limit_by_axes(limits_.acceleration, p.unit);
  p.rapid_rate = limit_by_axes(limits_.max_rate, p.unit) / 60.0;
  if (blocks_.empty() && at_rest()) {
    p.junction_sq = 0;
  } else {
    const double cos_theta = -dot(last_unit_, p.unit);
    if (!has_last_unit_ || cos_theta > 0.999999) {
      p.junction_sq = 0;  // no direction before, or a full reversal
    } else if (cos_theta < -0.999999) {
      p.junction_sq = kHuge;  // straight on
    } else {
      const geometry::Vec3 junction_unit = normalized(p.unit - last_unit_);
      const double junction_accel = limit_by_axes(limits_.acceleration, junction_unit);
      const double sin_half = std::sqrt(0.5 * (1.0 - cos_theta));
      p.junction_sq = junction_accel * limits_.junction_deviation * sin_half / (1.0 - sin_half);
    }
  }
  last_unit_ = p.unit;
  has_last_unit_ = true;
  blocks_.push_back(p);
  replan();
  return true;
}

void MotionQueue::replan() {
  const std::size_t n = blocks_.size();
  if (n == 0) return;
  for (std::size_t i = 1; i < n; ++i) {
    const double vn = nominal(blocks_[i]);
    const double vp = nominal(blocks_[i - 1]);
    blocks_[i].max_entry_sq = std::min({blocks_[i].junction_sq, vn * vn, vp * vp});
  }
  // Backward pass: every block must be able to stop at the end of the queue.
  double next_entry_sq = 0;
  for (std::size_t i = n - 1; i >= 1; --i) {
    Planned& b = blocks_[i];
    b.entry_sq = std::min(b.max_entry_sq, next_entry_sq + 2 * b.accel * b.length);
    next_entry_sq = b.entry_sq;
  }
  // Forward pass: no block can be entered faster than the one before allows.
  double reachable_sq = speed_ * speed_ + 2 * blocks_[0].accel * blocks_[0].remaining;
  for (std::size_t i = 1; i < n; ++i) {
    Planned& b = blocks_[i];
    b.entry_sq = std::min(b.entry_sq, reachable_sq);
    reachable_sq = b.entry_sq + 2 * b.accel * b.length;
  }
}

double MotionQueue::exit_speed() const {
  if (holding_ || blocks_.size() < 2) return 0;
  return std::sqrt(blocks_[1].entry_sq);
}

void MotionQueue::hold() { holding_ = true; }

void MotionQueue::resume() {
  holding_ = false;
  replan();
}

void MotionQueue::clear() {
  blocks_.clear();
  speed_ = 0;
  holding_ = false;
  has_last_unit_ = false;
}

void MotionQueue::set_overrides(double feed, double rapid) {
  feed_override_ = feed;
  rapid_override_ = rapid;
  replan();
}

MotionQueue::Advance MotionQueue::advance(double dt, const Traverse& on_traverse, bool stop_after_block) {
  Advance result;
  double left = dt;
  while (left > 0 && !blocks_.empty()) {
    if (holding_ && at_rest()) break;
    Planned& b = blocks_.front();
    if (b.remaining <= 1e-12) {  // nothing left to move: finish it now
      position_ = b.src.to;
      blocks_.pop_front();
      ++result.completed;
      if (blocks_.empty()) speed_ = 0;
      else replan();
      if (stop_after_block) break;
      continue;
    }
    const double a = b.accel;
    const double v = speed_;
    const double rem = b.remaining;
    // Choose the phase: constant acceleration `acc` over distance `span`.
    double acc = 0, span = rem;
    bool ends_at_rest = false;
    if (holding_) {
      acc = -a;
      const double stop = v * v / (2 * a);
      if (stop <= rem) {
        span = stop;
        ends_at_rest = true;
      }
    } else {
      const double vn = nominal(b);
      const double vx = std::min(exit_speed(), vn);
      const double brake = v > vx ? (v * v - vx * vx) / (2 * a) : 0;
      if (brake >= rem - 1e-12) {
        acc = rem > 0 ? -(v * v - vx * vx) / (2 * rem) : 0;
        span = rem;
      } else if (v < vn - 1e-9) {
        acc = a;
        const double peak_sq = std::min(vn * vn, (2 * a * rem + v * v + vx * vx) / 2);
        span = std::clamp((peak_sq - v * v) / (2 * a), 0.0, rem);
        if (span <= 1e-12) {  // rounding put us at the braking point
          acc = rem > 0 ? -(v * v - vx * vx) / (2 * rem) : 0;
          span = rem;
        }
      } else if (v > vn + 1e-9) {
        acc = -a;
        span = std::min(rem, (v * v - vn * vn) / (2 * a));
      } else {
        acc = 0;
        span = std::max(0.0, rem - (vn * vn - vx * vx) / (2 * a));
        if (span <= 0) span = rem;  // numerically at the braking point
        speed_ = vn;
      }
    }
    const double v0 = speed_;
    // Time to cover `span` with constant acceleration from v0.
    double t_phase;
    if (std::fabs(acc) < 1e-12) {
      t_phase = v0 > 0 ? span / v0 : kHuge;
    } else {
      const double disc = std::max(0.0, v0 * v0 + 2 * acc * span);
      t_phase = (std::sqrt(disc) - v0) / acc;
      if (t_phase < 0) t_phase = 0;
    }
    if (ends_at_rest && acc != 0) t_phase = v0 / -acc;
    double moved, spent;
    if (t_phase <= left) {
      moved = span;
      speed_ = ends_at_rest ? 0 : std::sqrt(std::max(0.0, v0 * v0 + 2 * acc * span));
      spent = t_phase;
      left -= t_phase;
    } else {
      moved = std::clamp(v0 * left + 0.5 * acc * left * left, 0.0, span);
      speed_ = std::max(0.0, v0 + acc * left);
      spent = left;
      left = 0;
    }
    result.time += spent;
    if (!b.src.rapid) {
      result.feed_time += spent;
      result.feed_length += moved;
      if (b.src.feed > 0) result.commanded_time += moved / (b.src.feed / 60.0);
    }
    const geometry::Vec3 a_pt = position_;
    b.remaining -= moved;
    const bool done = b.remaining <= 1e-9 * std::max(1.0, b.length);
    position_ = done ? b.src.to : b.src.to - b.unit * b.remaining;
    if (on_traverse && (moved > 0 || done)) on_traverse(a_pt, position_, b.src);
    if (done) {
      blocks_.pop_front();
      ++result.completed;
      if (blocks_.empty()) {
        // The end of the last block is a stop, held or not: a hold that was
        // braking into it is complete (rounding may leave a sliver of speed
        // with no block left to shed it in, and the hold would never end).
        speed_ = 0;
      } else {
        replan();
      }
      if (stop_after_block) break;
    }
    if (ends_at_rest && speed_ <= kRestSpeed) {
      speed_ = 0;
      break;
    }
  }
  return result;
}

double estimate_motion_time(const std::vector<MotionBlock>& blocks, const MotionLimits& limits) {
  MotionQueue q(limits);
  double t = 0;
  bool positioned = false;
  for (const MotionBlock& b : blocks) {
    if (!positioned) {
      q.set_position(b.from);
      positioned = true;
    }
    while (q.full()) t += q.advance(std::numeric_limits<double>::infinity(), {}, true).time;
    q.push(b);
  }
  while (!q.empty()) t += q.advance(std::numeric_limits<double>::infinity(), {}, true).time;
  return t;
}

}  // namespace cncstream::gcode
