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
#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <chrono>
#include <filesystem>
#include <functional>
#include <istream>
#include <memory>
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

// Plays entries at their times on an asio timer (the replay's clock starts
// at start()); each entry goes to `deliver` on the context's thread, and
// `done` is called after the last one.
class ReplayPlayer {
 public:
  ReplayPlayer(boost::asio::io_context& io, std::vector<ReplayEntry> entries);
  ~ReplayPlayer();
  ReplayPlayer(const ReplayPlayer&) = delete;
  ReplayPlayer& operator=(const ReplayPlayer&) = delete;
  void start(std::function<void(const ReplayEntry&)> deliver, std::function<void()> done);
  bool finished() const { return next_ >= entries_.size(); }
  // When the last entry is due, in ms from the start.
  double length_ms() const { return entries_.empty() ? 0 : entries_.back().at_ms; }

 private:
  void arm();

  boost::asio::steady_timer timer_;
  std::vector<ReplayEntry> entries_;
  std::size_t next_ = 0;
  std::chrono::steady_clock::time_point t0_;
  std::function<void(const ReplayEntry&)> deliver_;
  std::function<void()> done_;
  std::shared_ptr<bool> alive_;
};

}  // namespace cncstream::pendant
