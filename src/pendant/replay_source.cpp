#include "cncstream/pendant/replay_source.hpp"

#include <cctype>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace cncstream::pendant {

namespace {

[[noreturn]] void bad(const std::string& name, int line, const std::string& what) {
  throw std::invalid_argument(name + ":" + std::to_string(line) + ": " + what);
}

std::optional<std::uint8_t> hex_byte(const std::string& t) {
  if (t.empty() || t.size() > 2) return std::nullopt;
  unsigned v = 0;
  for (char c : t) {
    if (!std::isxdigit(static_cast<unsigned char>(c))) return std::nullopt;
    v = v * 16 + static_cast<unsigned>(std::isdigit(static_cast<unsigned char>(c)) ? c - '0'
                                                                                   : std::tolower(c) - 'a' + 10);
  }
  return static_cast<std::uint8_t>(v);
}

}  // namespace

std::vector<ReplayEntry> parse_replay(std::istream& in, const std::string& name) {
  std::vector<ReplayEntry> out;
  std::string text;
  int line_no = 0;
  double last_ms = 0;
  while (std::getline(in, text)) {
    ++line_no;
    if (const auto hash = text.find('#'); hash != std::string::npos) text.erase(hash);
    std::istringstream words(text);
    std::vector<std::string> tokens;
    for (std::string w; words >> w;) tokens.push_back(w);
    if (tokens.empty()) continue;
    ReplayEntry e;
    e.line = line_no;
    std::size_t used = 0;
    try {
      e.at_ms = std::stod(tokens[0], &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != tokens[0].size() || !std::isfinite(e.at_ms) || e.at_ms < 0)
      bad(name, line_no, "'" + tokens[0] + "' is not a time in milliseconds (a number >= 0 starts each line)");
    if (e.at_ms < last_ms)
      bad(name, line_no, "time " + tokens[0] + " ms is earlier than the line before (times must not decrease)");
    last_ms = e.at_ms;
    if (tokens.size() == 2 && (tokens[1] == "unplug" || tokens[1] == "plug")) {
      e.kind = tokens[1] == "unplug" ? ReplayKind::Unplug : ReplayKind::Plug;
      out.push_back(e);
      continue;
    }
    if (tokens.size() != 1 + e.report.size())
      bad(name, line_no,
          "expected the time and 8 report bytes in hex (or 'unplug' / 'plug'), got " +
              std::to_string(tokens.size() - 1) + " token" + (tokens.size() == 2 ? "" : "s") + " after the time");
    for (std::size_t i = 0; i < e.report.size(); ++i) {
      const auto b = hex_byte(tokens[i + 1]);
      if (!b) bad(name, line_no, "byte " + std::to_string(i) + " '" + tokens[i + 1] + "' is not a hex byte (00-ff)");
      e.report[i] = *b;
    }
    // A report the pendant could not send is a typo: say so now, not as a
    // log line in the middle of the replay.
    if (std::string why; !decode_report(e.report, &why)) bad(name, line_no, why);
    out.push_back(e);
  }
  return out;
}

std::vector<ReplayEntry> load_replay(const std::filesystem::path& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error("cannot read the replay file " + path.string());
  return parse_replay(f, path.string());
}

ReplayPlayer::ReplayPlayer(boost::asio::io_context& io, std::vector<ReplayEntry> entries)
    : timer_(io), entries_(std::move(entries)), alive_(std::make_shared<bool>(true)) {}

ReplayPlayer::~ReplayPlayer() {
  *alive_ = false;
  // Cancelling may throw system_error; a destructor that throws ends the
  // program, and the timer's handler checks *alive_ anyway.
  try {
    timer_.cancel();
  } catch (...) {
  }
}

void ReplayPlayer::start(std::function<void(const ReplayEntry&)> deliver, std::function<void()> done) {
  deliver_ = std::move(deliver);
  done_ = std::move(done);
  next_ = 0;
  t0_ = std::chrono::steady_clock::now();
  arm();
}

void ReplayPlayer::arm() {
  if (finished()) {
    if (done_) done_();
    return;
  }
  timer_.expires_at(t0_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                              std::chrono::duration<double, std::milli>(entries_[next_].at_ms)));
  std::weak_ptr<bool> alive = alive_;
  timer_.async_wait([this, alive](const boost::system::error_code& ec) {
    if (ec || !alive.lock()) return;
    // Every entry that is due now, in file order (several may share a time).
    const double now_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0_).count();
    while (!finished() && entries_[next_].at_ms <= now_ms) {
      const ReplayEntry& e = entries_[next_++];
      if (deliver_) deliver_(e);
      if (!alive.lock()) return;  // the consumer ended the replay
    }
    arm();
  });
}

}  // namespace cncstream::pendant
