#include "link_feed_job.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "cncstream/gcode/link_feed_limit.hpp"

namespace cncstream::jobs {

void limit_feed_to_link(ToolpathProgram& r, const gcode::StreamLink& link) {
  gcode::LinkFeedOptions o;
  o.link = link;
  gcode::LinkFeedResult res = gcode::limit_feed_to_link(r.gcode, o);
  const std::size_t lines = res.line_length.size();
  // Operation k runs from its first line to the next one's (1-based).
  for (std::size_t k = 0; k < r.operations.size(); ++k) {
    OperationSummary& op = r.operations[k];
    const std::size_t first = k == 0 ? 1 : op.first_line;
    const std::size_t last = k + 1 < r.operations.size() ? r.operations[k + 1].first_line - 1 : lines;
    double length = 0, below = 0, wire = std::numeric_limits<double>::infinity();
    for (std::size_t i = first; i <= last && i <= lines; ++i) {
      const double l = res.line_length[i - 1];
      if (l <= 0) continue;
      length += l;
      if (res.line_below[i - 1]) below += l;
      wire = std::min(wire, res.line_wire_feed[i - 1]);
    }
    op.link_checked = true;
    op.wire_feed = wire;
    op.share_below_feed = length > 0 ? below / length : 0.0;
  }
  if (res.length_below > 0)
    r.notes.push_back(fmt::format(
        "the link ({:.0f} bytes/s) cannot deliver the densest stretches at F{:.0f} (they stream at {:.0f} mm/min): F is "
        "lowered there, on {:.1f} % of the path, in {} changes",
        link.bytes_per_second, res.commanded_feed, res.wire_feed, 100.0 * res.share_below(), res.feed_changes));
  r.gcode = std::move(res.text);
}

}  // namespace cncstream::jobs
