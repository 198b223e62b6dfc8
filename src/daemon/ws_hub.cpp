#include "cncstream/daemon/ws_hub.hpp"

namespace cncstream::daemon {

void ClientQueue::push_status(const std::string& machine, Frame f) {
  auto [it, inserted] = status_.try_emplace(machine, f);
  if (!inserted) {
    it->second = std::move(f);
    ++replaced_;
  }
}

bool ClientQueue::push(Frame f) {
  if (fifo_.size() >= max_) return false;
  fifo_.push_back(std::move(f));
  return true;
}

Frame ClientQueue::pop() {
  if (!status_.empty()) {
    auto it = status_.begin();
    Frame f = std::move(it->second);
    status_.erase(it);
    return f;
  }
  if (fifo_.empty()) return nullptr;
  Frame f = std::move(fifo_.front());
  fifo_.pop_front();
  return f;
}

std::shared_ptr<WsClient> WsHub::add(std::string client_id, std::weak_ptr<WsPeer> peer) {
  if (full()) return nullptr;
  auto c = std::make_shared<WsClient>(queue_messages_);
  c->id = next_id_++;
  c->client_id = std::move(client_id);
  c->peer = std::move(peer);
  clients_[c->id] = c;
  return c;
}

void WsHub::remove(std::uint64_t id) { clients_.erase(id); }

std::size_t WsHub::count(const std::string& client_id) const {
  std::size_t n = 0;
  for (const auto& [id, c] : clients_) n += c->client_id == client_id;
  return n;
}

void WsHub::deliver(WsClient& c, Frame f, const std::string* status_machine) {
  auto peer = c.peer.lock();
  if (!peer) return;
  if (status_machine) {
    c.queue.push_status(*status_machine, std::move(f));
  } else if (!c.queue.push(std::move(f))) {
    peer->close_slow("too slow: more than the queue's limit of messages waiting");
    return;
  }
  peer->kick();
}

void WsHub::publish_status(const std::string& machine, const Frame& f) {
  // Copy: a peer closing inside deliver() may remove itself from the map.
  auto list = clients_;
  for (auto& [id, c] : list)
    if (c->wants(machine)) deliver(*c, f, &machine);
}

void WsHub::publish(const std::string& machine, const Frame& f) {
  auto list = clients_;
  for (auto& [id, c] : list)
    if (c->wants(machine)) deliver(*c, f, nullptr);
}

void WsHub::broadcast(const Frame& f) {
  auto list = clients_;
  for (auto& [id, c] : list) deliver(*c, f, nullptr);
}

void WsHub::send(WsClient& c, Frame f) { deliver(c, std::move(f), nullptr); }

}  // namespace cncstream::daemon
