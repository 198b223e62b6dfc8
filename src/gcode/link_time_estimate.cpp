// Run time over a link: the host streams with character counting, the wire
// carries the bytes at its rate, the firmware plans a line once it has
// arrived and the planner has room, and answers it then (which frees its
// bytes in the host's count). Line by line, in time, with the same planner
// as the simulator.
#include <algorithm>
#include <deque>
#include <limits>

#include "cncstream/gcode/program.hpp"

namespace cncstream::gcode {
namespace {

struct Streamed {
  std::vector<double> line_end;  // per line: when its last block finished
  double total = 0;
};

Streamed stream_through_link(const ProgramTrace& trace, const MotionLimits& limits, const StreamLink& link,
                             std::size_t line_count) {
  Streamed out;
  out.line_end.assign(line_count, 0.0);
  std::vector<char> moved(line_count, 0);
  const std::vector<MotionBlock> blocks = to_motion_blocks(trace.segments);
  const std::size_t lines = trace.line_bytes.size();
  MotionQueue q(limits, std::max<std::size_t>(1, link.planner_blocks));
  double t = 0;
  // Runs the motion on to time `until` (the queue may run dry before).
  const auto run_until = [&](double until) {
    while (t < until && !q.empty()) {
      const std::uint64_t tag = q.current()->tag;
      const auto a = q.advance(until - t, {}, true);
      t += a.time;
      if (a.completed > 0 && tag < line_count) out.line_end[tag] = t, moved[tag] = 1;
      if (a.time <= 0 && a.completed == 0) break;
    }
    t = std::max(t, until);
  };
  const auto finish_one_block = [&] {
    const std::uint64_t tag = q.current()->tag;
    const auto a = q.advance(std::numeric_limits<double>::infinity(), {}, true);
    t += a.time;
    if (a.completed > 0 && tag < line_count) out.line_end[tag] = t, moved[tag] = 1;
  };

  // The host: a line's bytes go out when the count of unanswered bytes
  // allows, after the bytes before them.
  const double budget = static_cast<double>(link.rx_bytes - std::min(link.rx_bytes - 1, link.rx_margin));
  const double byte_time = link.bytes_per_second > 0 ? 1.0 / link.bytes_per_second : 0.0;
  std::vector<double> arrival(lines, 0.0);
  double wire_free = 0, unanswered = 0;
  std::size_t next_send = 0;
  const auto host_sends = [&](double now) {
    for (; next_send < lines; ++next_send) {
      const double b = trace.line_bytes[next_send];
      if (b == 0) continue;
      if (unanswered + b > budget && unanswered > 0) break;
      const double start = std::max(wire_free, now);
      arrival[next_send] = wire_free = start + b * byte_time;
      unanswered += b;
    }
  };
  host_sends(0);
  const double plan_gap = link.blocks_per_second > 0 ? 1.0 / link.blocks_per_second : 0.0;
  double last_planned = -plan_gap;
  std::size_t bi = 0;
  bool positioned = false;
  for (std::size_t line = 0; line < lines; ++line) {
    const double b = trace.line_bytes[line];
    if (b == 0) continue;
    // The firmware waits for the line to arrive, then plans its blocks as
    // room frees, at most blocks_per_second of them.
    run_until(arrival[line]);
    for (; bi < blocks.size() && blocks[bi].tag == line; ++bi) {
      if (!positioned) q.set_position(blocks[bi].from), positioned = true;
      run_until(last_planned + plan_gap);
      while (q.full()) finish_one_block();
      q.push(blocks[bi]);
      last_planned = t;
    }
    // Answered: its bytes leave the host's count.
    unanswered -= b;
    host_sends(t);
  }
  // Blocks of lines the trace kept but that were not sent (none in practice).
  for (; bi < blocks.size(); ++bi) {
    while (q.full()) finish_one_block();
    q.push(blocks[bi]);
  }
  while (!q.empty()) finish_one_block();
  out.total = t;
  double last = 0;
  for (std::size_t i = 0; i < line_count; ++i) {
    if (moved[i]) last = std::max(last, out.line_end[i]);
    out.line_end[i] = last;
  }
  return out;
}

}  // namespace

TimeEstimate estimate_program_time(const ProgramTrace& trace, const MotionLimits& limits, const StreamLink& link) {
  if (link.unbounded() && link.planner_blocks == MotionQueue::kGrblPlannerBlocks) return estimate_program_time(trace, limits);
  TimeEstimate e;
  e.motion_seconds = stream_through_link(trace, limits, link, 0).total;
  e.dwell_seconds = trace.dwell_seconds;
  return e;
}

std::vector<double> estimate_line_end_times(const ProgramTrace& trace, const MotionLimits& limits,
                                            std::size_t line_count, const StreamLink& link) {
  if (link.unbounded() && link.planner_blocks == MotionQueue::kGrblPlannerBlocks)
    return estimate_line_end_times(trace, limits, line_count);
  return stream_through_link(trace, limits, link, line_count).line_end;
}

}  // namespace cncstream::gcode
