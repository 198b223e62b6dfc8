#pragma once
// Writing the program's displays (the jog DRO, the job panel, progress lines)
// to a terminal or a pipe.

#include <cstdio>
#include <string_view>

namespace cncstream::app {

// Writes `text` and flushes, so that a line shows at once. A display that can
// no longer be written (a closed terminal, a full pipe) must not stop what it
// shows, a jog or a job: the caller decides; false when a byte was not written.
inline bool put_text(std::FILE* out, std::string_view text) {
  const bool written = std::fwrite(text.data(), 1, text.size(), out) == text.size();
  return std::fflush(out) == 0 && written;
}

}  // namespace cncstream::app
