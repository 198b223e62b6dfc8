#pragma once
// GRBL character-counting flow control: the host mirrors the controller's RX
// buffer. Each line sent costs its length + 1 (newline); every `ok` or
// `error:N` frees exactly the oldest line. Lines marked `sync` (persistent
// writes) are sent alone: only when nothing is in flight, and nothing follows
// them until they are answered.
#include <cstddef>
#include <deque>
#include <optional>
#include <string>

#include "cncstream/protocol/line_cleaner.hpp"

namespace cncstream::protocol {

class CharacterCountingStream {
 public:
  // `rx_size` bytes in the controller, `margin` of them kept free.
  CharacterCountingStream(std::size_t rx_size, std::size_t margin);

  void set_rx_size(std::size_t rx_size);
  std::size_t capacity() const { return rx_size_ - margin_; }
  static std::size_t cost(const PreparedLine& l) { return l.text.size() + 1; }

  // Whether `l` may be sent now without overflowing the controller.
  bool can_send(const PreparedLine& l) const;
  // Records `l` as in flight and returns the bytes to write (text + '\n').
  // Precondition: can_send(l).
  std::string send(PreparedLine l);
  // An `ok` / `error:N` arrived: the oldest in-flight line is answered.
  // nullopt when nothing is in flight (a stale answer, e.g. just before a
  // reset banner) so callers can warn instead of corrupting the count.
  std::optional<PreparedLine> answer();

  std::size_t in_flight_bytes() const { return bytes_; }
  std::size_t in_flight_count() const { return fifo_.size(); }
  bool sync_in_flight() const { return !fifo_.empty() && fifo_.back().sync; }
  const std::deque<PreparedLine>& in_flight() const { return fifo_; }
  // A reset flushes the controller's buffer: forget everything in flight.
  void clear();

 private:
  std::size_t rx_size_;
  std::size_t margin_;
  std::size_t bytes_ = 0;
  std::deque<PreparedLine> fifo_;
};

}  // namespace cncstream::protocol
