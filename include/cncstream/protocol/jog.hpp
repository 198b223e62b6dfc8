#pragma once
// Jog command lines for GRBL-family $J=. Continuous jogging sends short G91
// segments (at most two in flight) whose length matches the feed over one
// segment time; the direction is normalised so a diagonal does not move
// sqrt(n) times farther than a single axis.
#include <array>
#include <string>

namespace cncstream::protocol {

struct JogDirection {
  std::array<double, 3> v{};  // X Y Z components; any scale, normalised by the planner
};

// One continuous-jog segment: `$J=G91 G21 X.. Y.. F..` covering feed * seconds.
// Throws std::invalid_argument for a zero direction or a non-positive feed.
std::string jog_segment_line(const JogDirection& dir, double feed_mm_min, double segment_s);

// The axis and feed words of a relative move of `length_mm` along `dir`
// ("X1.000Y-0.500F1000"): the Marlin engine jogs with relative G1 moves.
std::string relative_move_words(const JogDirection& dir, double length_mm, double feed_mm_min);

// A step jog of `distance_mm` along `dir` (incremental, millimetres).
std::string jog_step_line(const JogDirection& dir, double distance_mm, double feed_mm_min);

}  // namespace cncstream::protocol
