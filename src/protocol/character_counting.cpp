#include "cncstream/protocol/character_counting.hpp"

#include <stdexcept>

namespace cncstream::protocol {

CharacterCountingStream::CharacterCountingStream(std::size_t rx_size, std::size_t margin)
    : rx_size_(rx_size), margin_(margin) {
  if (margin_ >= rx_size_) throw std::invalid_argument("character counting: margin must be smaller than the RX size");
}

void CharacterCountingStream::set_rx_size(std::size_t rx_size) {
  if (margin_ >= rx_size) throw std::invalid_argument("character counting: margin must be smaller than the RX size");
  rx_size_ = rx_size;
}

bool CharacterCountingStream::can_send(const PreparedLine& l) const {
  if (sync_in_flight()) return false;
  if (l.sync && !fifo_.empty()) return false;
  return bytes_ + cost(l) <= capacity();
}

std::string CharacterCountingStream::send(PreparedLine l) {
  if (!can_send(l)) throw std::logic_error("character counting: line sent while it does not fit");
  std::string bytes = l.text + '\n';
  bytes_ += bytes.size();
  fifo_.push_back(std::move(l));
  return bytes;
}

std::optional<PreparedLine> CharacterCountingStream::answer() {
  if (fifo_.empty()) return std::nullopt;
  PreparedLine l = std::move(fifo_.front());
  fifo_.pop_front();
  bytes_ -= cost(l);
  return l;
}

void CharacterCountingStream::clear() {
  fifo_.clear();
  bytes_ = 0;
}

}  // namespace cncstream::protocol
