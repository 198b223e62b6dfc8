#include "cncstream/protocol/execution_estimate.hpp"

#include <algorithm>
#include <cctype>

namespace cncstream::protocol {

namespace {
// More than any firmware's planner (grblHAL's largest is 35 blocks by default).
constexpr std::size_t kKeep = 256;
}  // namespace

bool line_moves(std::string_view text) {
  int depth = 0;  // inside ( ) comments
  for (char c : text) {
    if (c == ';') return false;
    if (c == '(') ++depth;
    else if (c == ')' && depth > 0) --depth;
    else if (depth == 0) {
      const char u = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
      if (u == 'X' || u == 'Y' || u == 'Z' || u == 'A' || u == 'B' || u == 'C') return true;
    }
  }
  return false;
}

void ExecutionEstimate::reset() { *this = ExecutionEstimate{}; }

void ExecutionEstimate::on_answered(long source_line, std::string_view text) {
  last_answered_ = source_line;
  if (line_moves(text)) {
    moves_.push_back(source_line);
    if (moves_.size() > kKeep) moves_.pop_front();
    // A new block entered the planner; the next report says how many remain.
    ++queued_;
  }
  update();
}

void ExecutionEstimate::on_status(std::optional<int> planner_free, bool idle, int planner_blocks) {
  if (planner_free) queued_ = std::max(0, planner_blocks - *planner_free);
  else queued_ = idle ? 0 : planner_blocks;
  update();
}

void ExecutionEstimate::all_done() {
  queued_ = 0;
  update();
}

void ExecutionEstimate::update() {
  long line = last_answered_;
  if (queued_ > 0 && !moves_.empty()) {
    // The queued-th newest move is the one running (the running block is
    // still in the planner); with fewer moves known, the oldest of them.
    const std::size_t back = std::min<std::size_t>(static_cast<std::size_t>(queued_), moves_.size());
    line = moves_[moves_.size() - back];
  }
  // Never backwards: a report taken before an answer can say more blocks
  // are queued than the answers since.
  executing_ = std::max(executing_, line);
}

}  // namespace cncstream::protocol
