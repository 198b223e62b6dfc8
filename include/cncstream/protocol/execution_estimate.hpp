#pragma once
// Which file line the machine is executing. A controller answers `ok` when a
// line enters its planner, so the last answered line runs ahead of the
// motion by up to a planner's worth of moves (15 blocks on GRBL 1.1: often
// a minute at a slow feed). Progress and ETA shown to an operator follow
// this estimate instead: the moves still queued in the planner (from the
// status report's Bf: or Marlin's `ok P`) are taken off the answered ones.
//
// Approximation, on the safe side: a line that becomes several planner
// blocks (an arc, a long move split by the firmware) counts once here, so
// a full planner of arc segments puts the estimate earlier than the machine,
// never later.
#include <cstddef>
#include <deque>
#include <optional>
#include <string_view>

namespace cncstream::protocol {

class ExecutionEstimate {
 public:
  void reset();
  // A file line answered ok, in order. `text` is the line as sent: a line
  // with an axis word becomes planner blocks; the others (modal words, M
  // codes, comments) do not.
  void on_answered(long source_line, std::string_view text);
  // A status report: the planner's free blocks out of `planner_blocks` when
  // the report has them (GRBL's Bf:, only with $10 bit 1; Marlin's `ok P`).
  // Without them, a running controller is taken to have a full planner
  // (the streamer keeps it full) and an idle one an empty planner.
  void on_status(std::optional<int> planner_free, bool idle, int planner_blocks);
  // Every answered line has run (the job ended, the machine is idle with an
  // empty planner).
  void all_done();

  // 1-based file line, 0 before the first move ran.
  long executing_line() const { return executing_; }

 private:
  void update();

  std::deque<long> moves_;  // answered lines that move, newest last (at most kKeep)
  long last_answered_ = 0;
  int queued_ = 0;          // planner blocks still to run, including the one running
  long executing_ = 0;
};

// True when the line (as sent, comments stripped) has an axis word.
bool line_moves(std::string_view text);

}  // namespace cncstream::protocol
