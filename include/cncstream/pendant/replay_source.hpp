#pragma once
// Recorded pendant input, replayed instead of USB: for tests against the
// simulator, and for anyone debugging a pendant. One entry per line:
//
//   300 04 00 00 00 0f 11 03 00   # at 300 ms, this 8-byte report
//   900 unplug                    # the receiver vanishes (dead man)
//   1500 plug                     # and comes back
//
// The time is in milliseconds from the start of the replay (not
// decreasing); `#` starts a comment; blank lines are skipped. Bytes are hex,
// one or two digits each, exactly eight.
#include <filesystem>
#include <istream>
#include <string>
#include <vector>

#include "cncstream/pendant/whb04b_report.hpp"

namespace cncstream::pendant {

enum class ReplayKind { Report, Unplug, Plug };

struct ReplayEntry {
  double at_ms = 0;
  ReplayKind kind = ReplayKind::Report;
  InputReport report{};
  int line = 0;  // in the file, for messages
};

// Parses the text; `name` is used in error messages. Throws
// std::invalid_argument "NAME:LINE: ..." naming the bad token.
std::vector<ReplayEntry> parse_replay(std::istream& in, const std::string& name);
// Reads a file; throws std::runtime_error when it cannot be read.
std::vector<ReplayEntry> load_replay(const std::filesystem::path& path);

}  // namespace cncstream::pendant
