#pragma once
// GRBL-style look-ahead motion planning and execution in time.
//
// MotionQueue holds up to 15 straight blocks (GRBL's usable planner size).
// Each block's acceleration and rapid rate are limited per axis ($120-$122,
// $110-$112); the speed through a junction is limited by junction deviation
// ($11); entry speeds are re-planned (backward then forward pass) whenever a
// block arrives or an override changes. advance(dt) moves the tool along the
// blocks with trapezoidal speed profiles, exactly, for any dt; feed hold
// decelerates to rest at the blocks' accelerations. The simulator and the
// program time estimator share it, so they agree.
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <vector>

#include "cncstream/geometry/vec3.hpp"

namespace cncstream::gcode {

struct MotionLimits {
  geometry::Vec3 max_rate{500, 500, 500};      // mm/min per axis ($110-$112)
  geometry::Vec3 acceleration{10, 10, 10};     // mm/s^2 per axis ($120-$122)
  double junction_deviation = 0.01;  // mm ($11)
};

struct MotionBlock {
  geometry::Vec3 from, to;
  double feed = 0;     // mm/min; ignored for rapids
  bool rapid = false;
  std::int32_t line_number = 0;
  std::uint64_t tag = 0;  // caller's id (e.g. the source line index)
  // Jogs and probe moves run at their programmed feed: GRBL exempts them from
  // the feed override (PL_COND_FLAG_NO_FEED_OVERRIDE).
  bool no_feed_override = false;
};

class MotionQueue {
 public:
  static constexpr std::size_t kGrblPlannerBlocks = 15;

  explicit MotionQueue(const MotionLimits& limits = {}, std::size_t capacity = kGrblPlannerBlocks);

  void set_limits(const MotionLimits& limits);
  const MotionLimits& limits() const { return limits_; }
  std::size_t capacity() const { return capacity_; }
  std::size_t size() const { return blocks_.size(); }
  bool empty() const { return blocks_.empty(); }
  bool full() const { return blocks_.size() >= capacity_; }

  // Appends a block starting at the end of the last one (or the current
  // position). Zero-length blocks are ignored, as GRBL does: returns false.
  bool push(const MotionBlock& block);

  // Called for every straight piece the tool traverses.
  using Traverse = std::function<void(const geometry::Vec3& a, const geometry::Vec3& b, const MotionBlock& block)>;
  struct Advance {
    double time = 0;             // seconds of motion simulated (<= dt)
    std::size_t completed = 0;   // blocks finished
    // Of that time, the part spent on feed (non-rapid) blocks, the length
    // they covered and the time the same length takes at their programmed
    // feed: what a simulator needs to say how far a program fell below its F.
    double feed_time = 0, feed_length = 0, commanded_time = 0;
  };
  // Moves for up to dt seconds. Returns early when the queue runs dry, when a
  // hold comes to rest, or, with stop_after_block, when a block completes.
  Advance advance(double dt, const Traverse& on_traverse = {}, bool stop_after_block = false);

  void hold();    // decelerate to rest and stay there
  void resume();  // accelerate again from rest
  bool holding() const { return holding_; }
  bool at_rest() const { return speed_ <= kRestSpeed; }
  // Drops every block; the tool stays where it is (reset, jog cancel).
  void clear();

  geometry::Vec3 position() const { return position_; }
  void set_position(const geometry::Vec3& p);  // only meaningful when empty
  double speed() const { return speed_; }  // mm/s
  const MotionBlock* current() const { return blocks_.empty() ? nullptr : &blocks_.front().src; }

  // 1.0 = 100 %. Feed override applies to feed moves, rapid override to rapids.
  void set_overrides(double feed, double rapid);

  static constexpr double kRestSpeed = 1e-9;

 private:
  struct Planned {
    MotionBlock src;
    geometry::Vec3 unit;
    double length = 0;
    double remaining = 0;
    double accel = 0;        // mm/s^2 along the block
    double rapid_rate = 0;   // mm/s along the block
    double junction_sq = 0;  // (mm/s)^2 limit at its start
    double max_entry_sq = 0;
    double entry_sq = 0;
  };
  double nominal(const Planned& b) const;
  void replan();
  double exit_speed() const;

  MotionLimits limits_;
  std::size_t capacity_;
  std::deque<Planned> blocks_;
  geometry::Vec3 position_{};
  geometry::Vec3 last_unit_{};
  bool has_last_unit_ = false;
  double speed_ = 0;
  bool holding_ = false;
  double feed_override_ = 1.0;
  double rapid_override_ = 1.0;
};

// Time to run the blocks through a 15-block planner that is always kept full
// (a host that streams fast enough), from rest to rest, in seconds.
double estimate_motion_time(const std::vector<MotionBlock>& blocks, const MotionLimits& limits);

}  // namespace cncstream::gcode
