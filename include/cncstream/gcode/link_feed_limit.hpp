#pragma once
// A program that cannot stream at its feed says so and adapts. For every
// window of `window` consecutive feed moves, the wire carries their bytes in
// bytes / rate seconds; at feed F they take length / F. Where the bytes take
// longer the planner would run dry, so the feed there is lowered to what
// arrives in time (length / (bytes / rate)), rounded down to one of a few
// levels of the commanded feed, written only where it changes, and the
// commanded feed is restored after. A feed is never raised. The result,
// measured again by the same rule, never starves.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "cncstream/gcode/stream_link.hpp"

namespace cncstream::gcode {

struct LinkFeedOptions {
  StreamLink link;
  std::size_t window = 50;  // feed moves per window (streamable.py's measure)
  // The feeds written, as fractions of the commanded one, largest first.
  std::vector<double> levels{1.0, 0.8, 0.6, 0.45, 0.3, 0.2, 0.1, 0.05};
};

struct LinkFeedResult {
  std::string text;             // the program with the lowered feeds
  double wire_feed = 0;         // mm/min: what the worst window of the original allows (0: no feed moves)
  double commanded_feed = 0;    // mm/min: the highest F of its feed moves
  double feed_length = 0;       // mm of feed moves
  double length_below = 0;      // mm of them now below their commanded feed
  std::size_t feed_changes = 0; // F words added
  // Per program line (0-based): the feed-move length on it, the feed the
  // wire allows there (infinite: no limit; 0 on lines without a feed move)
  // and whether it now runs below its commanded feed.
  std::vector<double> line_length, line_wire_feed;
  std::vector<char> line_below;
  double share_below() const { return feed_length > 0 ? length_below / feed_length : 0.0; }
};

// The lowest feed (mm/min) any window of the moves streams at without
// starving: min over windows of length / (bytes / rate). `lengths` and
// `bytes` per feed move. Infinite for an unbounded link or too few moves
// are taken as one window.
double streamable_feed(const std::vector<double>& lengths, const std::vector<double>& bytes, double bytes_per_second,
                       std::size_t window);

// Feeds (mm/min) per move: the commanded one, or lower where a window holding
// the move starves (see above). Same size as the inputs.
std::vector<double> link_limited_feeds(const std::vector<double>& lengths, const std::vector<double>& bytes,
                                       const std::vector<double>& commanded, const LinkFeedOptions& options);

// The whole program (G1/G2/G3 lines are the feed moves; G0 and other lines
// pass unchanged). Throws std::invalid_argument on a line with an error.
LinkFeedResult limit_feed_to_link(std::string_view program, const LinkFeedOptions& options);

}  // namespace cncstream::gcode
