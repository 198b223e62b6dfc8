#include "cncstream/session/job_input.hpp"

#include <algorithm>

#include "cncstream/gcode/program_pause.hpp"

namespace cncstream::session {

std::optional<PauseAt> pause_at(const std::vector<std::string>& lines, const std::vector<long>& source_lines,
                                long answered) {
  std::size_t next = 0;  // the entry after the last answered one
  if (source_lines.empty()) {
    next = static_cast<std::size_t>(std::max(0L, answered));
  } else {
    const auto it = std::upper_bound(source_lines.begin(), source_lines.end(), answered);
    next = static_cast<std::size_t>(it - source_lines.begin());
  }
  // Comment lines before the pause may not have been sent: look past them.
  std::size_t ahead = next;
  while (ahead < lines.size() && gcode::has_no_words(lines[ahead])) ++ahead;
  for (const std::size_t k : {ahead, next - 1}) {
    if (k >= lines.size()) continue;  // next - 1 wraps below the first
    if (auto note = gcode::program_pause_note(lines, k)) {
      const long line = source_lines.empty() ? static_cast<long>(k) + 1 : source_lines[k];
      return PauseAt{line, std::move(*note)};
    }
  }
  return std::nullopt;
}

}  // namespace cncstream::session
