#pragma once
// Does a program keep a GRBL planner fed over a real serial link? Streams it
// (or its densest stretch) to the simulated machine, with GRBL character
// counting (128-byte RX buffer, one byte spare), in virtual time, three times:
//   paced:        115,200 baud, GRBL's 15-block planner (the real machine);
//   unthrottled:  bytes arrive at once, 15 blocks;
//   deep planner: bytes at once, 1,000 blocks (no look-ahead limit in practice).
// Two limits can hold a program below its F: the wire (paced against
// unthrottled: the planner runs dry waiting for bytes) and the look-ahead
// (unthrottled against the deep planner: GRBL must be able to stop within
// its 15 planned blocks, v <= sqrt(2 a * sum of their lengths)). A program
// keeps the planner fed when neither costs more than the margin.
//
//   const auto r = simtest::check_streaming("part.nc");          // densest 20,000 lines
//   EXPECT_TRUE(r.keeps_planner_fed()) << r.describe();
//   EXPECT_LE(r.slowdown(), 1.05) << r.describe();                // the wire alone
//
// The machine has a router's settings ($110-$112 6,000 mm/min, $120-$122
// 500 mm/s^2, $11 0.01 mm). The host answers each `ok` within host_step
// seconds of virtual time (the same on both links).
#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <deque>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cncsim/machine.hpp"
#include "cncstream/gcode/line_lexer.hpp"
#include "cncstream/gcode/program.hpp"

namespace simtest {

struct StreamRun {
  double seconds = 0;  // first byte sent to the last move done
  cncsim::LinkStats link;
  std::size_t lines = 0, answered = 0, rx_dropped = 0;
};

struct StreamingOptions {
  double baud = 115200;
  double max_rate = 6000;     // $110-$112, mm/min
  double acceleration = 500;  // $120-$122, mm/s^2
  double host_step = 0.00025; // s of virtual time between the host's looks at the port
  double max_seconds = 36000;
};

// The lines as a host sends them (cleaned: upper case, no spaces or comments;
// empty ones left out), streamed with character counting until every one is
// answered and the machine is idle.
inline StreamRun stream_lines(const std::vector<std::string>& lines, double link_bytes_per_second,
                              const StreamingOptions& o = {}, std::size_t planner_blocks = cncsim::kPlannerBlocks) {
  cncsim::MachineOptions mo;
  mo.planner_blocks = planner_blocks;
  mo.strict = true;  // a host that overflows the RX buffer is a bug in this helper
  cncsim::Machine m(mo);
  for (int axis = 0; axis < 3; ++axis) {
    for (const std::string& setting : {fmt::format("$11{}={}", axis, o.max_rate), fmt::format("$12{}={}", axis, o.acceleration)}) {
      m.receive(setting + "\n");
      m.run_until_idle();
    }
  }
  m.take_output();
  // The settings went in unthrottled; from here on the link is the one under test.
  StreamRun run;
  run.lines = lines.size();
  const double start = m.now();
  m.set_link_rate(link_bytes_per_second);
  constexpr std::size_t kBudget = cncsim::kRxBufferSize - 1;
  std::deque<std::size_t> in_flight;
  std::size_t used = 0, next = 0;
  std::string pending;
  while (m.now() - start < o.max_seconds) {
    while (next < lines.size() && used + lines[next].size() + 1 <= kBudget) {
      m.receive(lines[next] + "\n");
      in_flight.push_back(lines[next].size() + 1);
      used += lines[next].size() + 1;
      ++next;
    }
    m.advance(o.host_step);
    pending += m.take_output();
    std::size_t at = 0;
    for (std::size_t nl; (nl = pending.find('\n', at)) != std::string::npos; at = nl + 1) {
      std::string line = pending.substr(at, nl - at);
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (line == "ok" || line.rfind("error:", 0) == 0) {
        if (line != "ok") throw std::runtime_error("the machine answered " + line + " to a line of the program");
        if (in_flight.empty()) throw std::runtime_error("an answer with no line in flight");
        used -= in_flight.front();
        in_flight.pop_front();
        ++run.answered;
      }
    }
    pending.erase(0, at);
    if (next == lines.size() && in_flight.empty() && !m.busy()) break;
  }
  run.seconds = m.now() - start;
  run.link = m.link_stats();
  run.rx_dropped = m.rx_bytes_dropped();
  return run;
}

// The cleaned lines of a program file, in order.
inline std::vector<std::string> program_lines(const std::filesystem::path& nc) {
  std::ifstream in(nc);
  if (!in) throw std::runtime_error("cannot read " + nc.string());
  std::vector<std::string> out;
  for (std::string raw; std::getline(in, raw);) {
    const auto c = cncstream::gcode::clean_line(raw);
    if (c.overflow) throw std::runtime_error(nc.string() + ": a line too long for GRBL: " + raw);
    if (!c.text.empty() && c.text != "%") out.push_back(c.text);
  }
  return out;
}

// The `count` consecutive lines whose bytes per mm of feed moves is highest
// (streamable.py's measure, over one window of `count` lines), each
// program's own lines, preceded by what makes them runnable on their own:
// millimetres, absolute, the plane, a rapid to where the stretch starts and
// its motion mode and feed. All lines when the program has no more.
inline std::vector<std::string> densest_stretch(const std::vector<std::string>& lines, std::size_t count) {
  namespace gc = cncstream::gcode;
  std::string text;
  for (const auto& l : lines) text += l + "\n";
  const gc::ProgramTrace trace = gc::trace_program(text);
  if (!trace.errors.empty()) throw std::runtime_error("the program has errors: " + trace.errors.front().message());
  std::size_t first = 0;
  if (lines.size() > count) {
    std::vector<double> feed_mm(lines.size() + 1, 0.0), bytes(lines.size() + 1, 0.0);
    std::vector<double> per_line(lines.size(), 0.0);
    for (const auto& s : trace.segments)
      if (!s.rapid) per_line[s.source_line] += cncstream::geometry::norm(s.to - s.from);
    for (std::size_t i = 0; i < lines.size(); ++i) {
      feed_mm[i + 1] = feed_mm[i] + per_line[i];
      bytes[i + 1] = bytes[i] + static_cast<double>(lines[i].size() + 1);
    }
    double worst = -1;
    for (std::size_t i = 0; i + count <= lines.size(); ++i) {
      const double mm = feed_mm[i + count] - feed_mm[i];
      const double density = mm > 0 ? (bytes[i + count] - bytes[i]) / mm : 0.0;
      if (density > worst) worst = density, first = i;
    }
  }
  const std::size_t last = std::min(lines.size(), first + count);
  std::vector<std::string> out;
  if (first > 0) {
    const gc::ParserState s = gc::state_before_line(text, first);
    const cncstream::geometry::Vec3 p = s.position;  // machine = work: the simulator's offsets are zero
    const char* plane = s.modal.plane == gc::Plane::XY ? "G17" : s.modal.plane == gc::Plane::ZX ? "G18" : "G19";
    out.push_back(std::string("G21G90G94") + plane);
    out.push_back(fmt::format("G0Z{:.3f}", p.z + 5.0));
    out.push_back(fmt::format("G0X{:.3f}Y{:.3f}", p.x, p.y));
    out.push_back(fmt::format("G1Z{:.3f}F{:.0f}", p.z, std::max(1.0, s.feed_rate)));
    const gc::MotionMode mm = s.modal.motion;
    const int motion = mm == gc::MotionMode::Rapid ? 0 : mm == gc::MotionMode::ArcCW ? 2 : mm == gc::MotionMode::ArcCCW ? 3 : 1;
    out.push_back(fmt::format("G{}", motion));
  }
  out.insert(out.end(), lines.begin() + static_cast<std::ptrdiff_t>(first), lines.begin() + static_cast<std::ptrdiff_t>(last));
  return out;
}

inline constexpr std::size_t kDeepPlannerBlocks = 1000;

struct StreamingCheck {
  StreamRun paced, unthrottled, deep;
  double baud = 0;
  std::size_t lines = 0;
  // What the wire costs: job time on the paced link over that unthrottled.
  double slowdown() const { return unthrottled.seconds > 0 ? paced.seconds / unthrottled.seconds : 0.0; }
  // What the 15-block look-ahead costs: unthrottled over the deep planner.
  double lookahead_slowdown() const { return deep.seconds > 0 ? unthrottled.seconds / deep.seconds : 0.0; }
  bool keeps_planner_fed(double margin = 0.05) const {
    return slowdown() <= 1 + margin && lookahead_slowdown() <= 1 + margin;
  }
  std::string describe() const {
    return fmt::format(
        "{} lines: {:.3f} s at {:.0f} baud, {:.3f} s unthrottled ({:.1f} % longer on the wire), {:.3f} s with a deep "
        "planner ({:.1f} % longer with 15 blocks); at {:.0f} baud the planner starved {:.3f} s (dry {:.3f} s), feed "
        "achieved {:.0f} of {:.0f} mm/min commanded (unthrottled {:.0f}, deep planner {:.0f})",
        lines, paced.seconds, baud, unthrottled.seconds, (slowdown() - 1) * 100, deep.seconds,
        (lookahead_slowdown() - 1) * 100, baud, paced.link.starved_seconds, paced.link.dry_seconds,
        paced.link.achieved_feed(), paced.link.commanded_feed(), unthrottled.link.achieved_feed(),
        deep.link.achieved_feed());
  }
};

// The whole check on a .nc file: its densest `count` lines on both links.
inline StreamingCheck check_streaming(const std::filesystem::path& nc, std::size_t count = 20000,
                                      const StreamingOptions& o = {}) {
  const auto lines = densest_stretch(program_lines(nc), count);
  StreamingCheck c;
  c.baud = o.baud;
  c.lines = lines.size();
  c.paced = stream_lines(lines, cncsim::link_bytes_per_second_for_baud(o.baud), o);
  c.unthrottled = stream_lines(lines, 0, o);
  c.deep = stream_lines(lines, 0, o, kDeepPlannerBlocks);
  if (c.paced.answered != lines.size() || c.unthrottled.answered != lines.size() || c.deep.answered != lines.size())
    throw std::runtime_error(fmt::format("not every line was answered ({} and {} of {}) within {} s", c.paced.answered,
                                         c.unthrottled.answered, lines.size(), o.max_seconds));
  return c;
}

}  // namespace simtest
