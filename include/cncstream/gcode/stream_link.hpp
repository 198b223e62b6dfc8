#pragma once
// The link a program streams over, as far as its run time depends on it:
// how fast bytes arrive, how many the controller's RX buffer holds (a GRBL
// streamer keeps at most that many, less a spare byte, unanswered), how many
// moves its planner holds ahead (the look-ahead: it can only run as fast as
// it can stop within them) and how many blocks a second it can plan.
// Protocol-free numbers: the firmware profile fills them
// (protocol/link_model.hpp).
#include <cstddef>

namespace cncstream::gcode {

struct StreamLink {
  double bytes_per_second = 0;      // 0: unbounded (native USB, or the link not modelled)
  std::size_t rx_bytes = 128;       // RX buffer; the streamer keeps rx_margin of it free
  std::size_t rx_margin = 1;
  std::size_t planner_blocks = 15;
  double blocks_per_second = 0;     // the firmware's planning rate; 0: not modelled
  // Only the planner's depth matters: the old full-planner estimate.
  bool unbounded() const { return bytes_per_second <= 0 && blocks_per_second <= 0; }
};

// 8-N-1: a start and a stop bit around each byte.
inline double bytes_per_second_for_baud(double baud) { return baud / 10.0; }

}  // namespace cncstream::gcode
