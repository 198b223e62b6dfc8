#include "cncstream/gcode/program.hpp"

#include <algorithm>
#include <limits>

#include "cncstream/gcode/arc_segments.hpp"
#include "cncstream/gcode/grbl_codes.hpp"
#include "cncstream/gcode/line_lexer.hpp"

namespace cncstream::gcode {
namespace {

bool carries_no_gcode(const CleanLine& c) {
  return !c.overflow && (c.text.empty() || c.text == "%" || c.text.front() == '$');
}

}  // namespace

std::vector<double> estimate_line_end_times(const ProgramTrace& trace, const MotionLimits& limits,
                                            std::size_t line_count) {
  std::vector<double> end(line_count, 0.0);
  std::vector<char> seen(line_count, 0);
  MotionQueue q(limits);
  double t = 0;
  auto step = [&] {
    const std::uint64_t tag = q.current()->tag;
    const auto a = q.advance(std::numeric_limits<double>::infinity(), {}, true);
    t += a.time;
    if (a.completed > 0 && tag < line_count) {
      end[tag] = t;  // a later block of the same line moves it later
      seen[tag] = 1;
    }
  };
  bool positioned = false;
  for (const MotionBlock& b : to_motion_blocks(trace.segments)) {
    if (!positioned) {
      q.set_position(b.from);
      positioned = true;
    }
    while (q.full()) step();
    q.push(b);
  }
  while (!q.empty()) step();
  double last = 0;
  for (std::size_t i = 0; i < line_count; ++i) {
    if (seen[i]) last = std::max(last, end[i]);
    end[i] = last;
  }
  return end;
}

std::vector<std::string_view> split_lines(std::string_view text) {
  std::vector<std::string_view> lines;
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) {
      lines.push_back(text.substr(start));
      break;
    }
    lines.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  return lines;
}

std::string LineError::message() const {
  return "line " + std::to_string(line + 1) + ": error:" + std::to_string(status) + ": " + text;
}

ProgramTrace trace_program(std::string_view text, const ProgramOptions& options) {
  ProgramTrace trace;
  ParserState state = options.initial;
  const auto lines = split_lines(text);
  trace.lines = lines.size();
  trace.line_bytes.assign(lines.size(), 0);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const CleanLine c = clean_line(lines[i]);
    if (!c.text.empty() && c.text != "%") trace.line_bytes[i] = static_cast<std::uint32_t>(c.text.size() + 1);
    if (carries_no_gcode(c)) continue;
    BlockResult r;
    if (c.overflow) {
      r.status = grbl::kOverflow;
    } else {
      r = execute_block(state, c.text);
    }
    if (!r.ok()) {
      trace.errors.push_back({i, r.status, std::string(lines[i])});
      if (options.stop_at_first_error) break;
      continue;
    }
    const geometry::Vec3 wco = r.state.wco();
    for (const Action& a : r.actions) {
      if (const auto* m = std::get_if<LinearMove>(&a)) {
        if (m->from == m->to) continue;
        trace.segments.push_back({m->from, m->to, wco, m->rapid, m->feed, i});
      } else if (const auto* arc = std::get_if<ArcMove>(&a)) {
        const ArcChords chords = arc_chords(*arc, options.arc_tolerance);
        geometry::Vec3 p = arc->from;
        for (const geometry::Vec3& q : chords.points) {
          trace.segments.push_back({p, q, wco, false, chords.feed, i});
          p = q;
        }
      } else if (const auto* pr = std::get_if<ProbeMove>(&a)) {
        trace.segments.push_back({pr->from, pr->to, wco, false, pr->feed, i});
      } else if (const auto* d = std::get_if<Dwell>(&a)) {
        trace.dwell_seconds += d->seconds;
      }
    }
    state = r.state;
  }
  trace.final_state = state;
  return trace;
}

ParserState state_before_line(std::string_view text, std::size_t line, const ParserState& initial) {
  ParserState state = initial;
  const auto lines = split_lines(text);
  for (std::size_t i = 0; i < lines.size() && i < line; ++i) {
    const CleanLine c = clean_line(lines[i]);
    if (carries_no_gcode(c) || c.overflow) continue;
    BlockResult r = execute_block(state, c.text);
    if (r.ok()) state = r.state;
  }
  return state;
}

std::vector<MotionBlock> to_motion_blocks(const std::vector<PathSegment>& segments) {
  std::vector<MotionBlock> blocks;
  blocks.reserve(segments.size());
  for (const PathSegment& s : segments)
    blocks.push_back({s.from, s.to, s.feed, s.rapid, 0, s.source_line});
  return blocks;
}

TimeEstimate estimate_program_time(const ProgramTrace& trace, const MotionLimits& limits) {
  TimeEstimate t;
  t.motion_seconds = estimate_motion_time(to_motion_blocks(trace.segments), limits);
  t.dwell_seconds = trace.dwell_seconds;
  return t;
}

}  // namespace cncstream::gcode
