#include "cncstream/gcode/link_feed_limit.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <deque>
#include <limits>
#include <stdexcept>

#include "cncstream/gcode/line_lexer.hpp"
#include "cncstream/gcode/program.hpp"

namespace cncstream::gcode {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Per move: the lowest feed over the windows that hold it.
std::vector<double> window_feeds(const std::vector<double>& lengths, const std::vector<double>& bytes, double rate,
                                 std::size_t window) {
  const std::size_t n = lengths.size();
  std::vector<double> allowed(n, kInf);
  if (rate <= 0 || n == 0) return allowed;
  const std::size_t w = std::clamp<std::size_t>(window, 1, n);
  std::vector<double> per_window(n - w + 1);
  double len = 0, b = 0;
  for (std::size_t i = 0; i < w; ++i) len += lengths[i], b += bytes[i];
  for (std::size_t s = 0;; ++s) {
    per_window[s] = b > 0 ? len / (b / rate) * 60.0 : kInf;
    if (s + w >= n) break;
    len += lengths[s + w] - lengths[s];
    b += bytes[s + w] - bytes[s];
  }
  // Sliding minimum over the windows holding move i: starts i-w+1 .. i.
  std::deque<std::size_t> q;
  for (std::size_t i = 0; i < n; ++i) {
    if (i < per_window.size()) {
      while (!q.empty() && per_window[q.back()] >= per_window[i]) q.pop_back();
      q.push_back(i);
    }
    while (q.front() + w <= i) q.pop_front();
    allowed[i] = per_window[q.front()];
  }
  return allowed;
}

}  // namespace

double streamable_feed(const std::vector<double>& lengths, const std::vector<double>& bytes, double bytes_per_second,
                       std::size_t window) {
  const auto f = window_feeds(lengths, bytes, bytes_per_second, window);
  return f.empty() ? kInf : *std::min_element(f.begin(), f.end());
}

std::vector<double> link_limited_feeds(const std::vector<double>& lengths, const std::vector<double>& bytes,
                                       const std::vector<double>& commanded, const LinkFeedOptions& o) {
  const auto allowed = window_feeds(lengths, bytes, o.link.bytes_per_second, o.window);
  std::vector<double> out(commanded);
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (allowed[i] >= commanded[i]) continue;
    // The largest level at or below what arrives in time.
    double f = 0;
    for (double level : o.levels) {
      if (commanded[i] * level <= allowed[i]) {
        f = commanded[i] * level;
        break;
      }
    }
    if (f <= 0) f = allowed[i];  // below every level: exactly what arrives
    out[i] = std::floor(f);      // F is written in whole mm/min, never rounded up
  }
  return out;
}

LinkFeedResult limit_feed_to_link(std::string_view program, const LinkFeedOptions& o) {
  LinkFeedResult r;
  if (o.link.bytes_per_second <= 0) {  // native USB: the wire never binds
    r.text = std::string(program);
    return r;
  }
  const ProgramTrace trace = trace_program(program);
  if (!trace.errors.empty()) throw std::invalid_argument("cannot limit the feed: " + trace.errors.front().message());
  const auto lines = split_lines(program);
  // The feed moves, by line: length and commanded feed.
  std::vector<double> line_length(lines.size(), 0.0), line_feed(lines.size(), 0.0);
  for (const PathSegment& s : trace.segments) {
    if (s.rapid) continue;
    line_length[s.source_line] += norm(s.to - s.from);
    line_feed[s.source_line] = s.feed;
  }
  std::vector<std::size_t> move_line;
  std::vector<double> lengths, commanded;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (line_length[i] <= 0) continue;
    move_line.push_back(i);
    lengths.push_back(line_length[i]);
    commanded.push_back(line_feed[i]);
    r.feed_length += line_length[i];
    r.commanded_feed = std::max(r.commanded_feed, line_feed[i]);
  }
  // Bytes per move as they will be sent: an F word added where the feed
  // changes costs bytes too, so measure again after writing and lower once
  // more where that made a window starve.
  std::vector<double> extra(lengths.size(), 0.0);
  std::vector<double> feeds = commanded;
  std::string text;
  for (int pass = 0; pass < 4; ++pass) {
    std::vector<double> bytes(lengths.size());
    for (std::size_t k = 0; k < lengths.size(); ++k)
      bytes[k] = static_cast<double>(grbl_line_cost(lines[move_line[k]])) + extra[k];
    if (pass == 0) {
      r.wire_feed = streamable_feed(lengths, bytes, o.link.bytes_per_second, o.window);
      const auto allowed = window_feeds(lengths, bytes, o.link.bytes_per_second, o.window);
      r.line_wire_feed.assign(lines.size(), 0.0);
      for (std::size_t m = 0; m < allowed.size(); ++m) r.line_wire_feed[move_line[m]] = allowed[m];
    }
    const auto lowered = link_limited_feeds(lengths, bytes, commanded, o);
    for (std::size_t k = 0; k < feeds.size(); ++k) feeds[k] = std::min(feeds[k], lowered[k]);
    // Write: a feed move's own F word is replaced by the feed wanted there
    // when it differs from the one in force.
    text.clear();
    std::fill(extra.begin(), extra.end(), 0.0);
    r.feed_changes = 0;
    double in_force = -1;
    bool program_feed = false;  // the F in force is one a line of the program set, as commanded
    std::size_t k = 0;
    bool starves = false;
    for (std::size_t i = 0; i < lines.size(); ++i) {
      std::string line(lines[i]);
      const bool move = k < move_line.size() && move_line[k] == i;
      const CleanLine c = clean_line(line);
      const auto f_at = c.text.find('F');
      if (!move) {
        if (f_at != std::string::npos) program_feed = true;  // the program set its own
        text += line;
        text += '\n';
        continue;
      }
      const double want = feeds[k];
      const bool in_effect = program_feed ? want == commanded[k] : want == in_force;
      program_feed = false;
      if (!in_effect || (f_at != std::string::npos && want != commanded[k])) {
        // Strip the line's own F (cleaned form) and write the wanted one.
        std::string cleaned = c.text;
        if (f_at != std::string::npos) {
          std::size_t end = f_at + 1;
          while (end < cleaned.size() && (std::isdigit(static_cast<unsigned char>(cleaned[end])) || cleaned[end] == '.' ||
                                          cleaned[end] == '-' || cleaned[end] == '+'))
            ++end;
          cleaned.erase(f_at, end - f_at);
        }
        const std::string fw = fmt::format("F{:.0f}", want);
        if (want != commanded[k] || f_at == std::string::npos) ++r.feed_changes;
        extra[k] = static_cast<double>(cleaned.size() + fw.size() + 1) -
                   static_cast<double>(grbl_line_cost(lines[move_line[k]]));
        line = cleaned + fw;
        in_force = want;
      }
      in_force = want;
      text += line;
      text += '\n';
      ++k;
    }
    // Measured again with the bytes as written.
    std::vector<double> written(lengths.size());
    for (std::size_t m = 0; m < lengths.size(); ++m)
      written[m] = static_cast<double>(grbl_line_cost(lines[move_line[m]])) + extra[m];
    const auto check = window_feeds(lengths, written, o.link.bytes_per_second, o.window);
    for (std::size_t m = 0; m < feeds.size(); ++m) starves = starves || check[m] < feeds[m] - 1e-9;
    if (!starves) break;
  }
  r.text = std::move(text);
  r.length_below = 0;
  r.line_length = std::move(line_length);
  r.line_below.assign(lines.size(), 0);
  for (std::size_t k = 0; k < feeds.size(); ++k) {
    if (feeds[k] >= commanded[k]) continue;
    r.length_below += lengths[k];
    r.line_below[move_line[k]] = 1;
  }
  return r;
}

}  // namespace cncstream::gcode
