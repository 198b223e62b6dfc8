#pragma once
// The WebSocket clients and what each is sent. Status is coalesced per client:
// only the latest undelivered status per machine is kept, so a slow reader
// gets fewer frames, never stale ones, and never holds up the machine or the
// other clients. Other messages queue in order up to a bound; a client whose
// queue overflows is dropped. Everything here runs on the event loop's
// thread; a message is serialised once and shared by every client.
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

namespace cncstream::daemon {

using Frame = std::shared_ptr<const std::string>;

class ClientQueue {
 public:
  explicit ClientQueue(std::size_t max_messages) : max_(max_messages) {}
  // Replaces the machine's undelivered status, if any.
  void push_status(const std::string& machine, Frame f);
  // False: the queue is full (the client is too slow and must be dropped).
  bool push(Frame f);
  // The next frame to write: statuses first (each machine's latest), then
  // the other messages in order. Null when empty.
  Frame pop();
  bool empty() const { return status_.empty() && fifo_.empty(); }
  std::size_t size() const { return status_.size() + fifo_.size(); }
  std::uint64_t statuses_replaced() const { return replaced_; }

 private:
  std::size_t max_;
  std::map<std::string, Frame> status_;
  std::deque<Frame> fifo_;
  std::uint64_t replaced_ = 0;
};

// What the hub needs from a connection (http_server.cpp's WebSocket session).
class WsPeer {
 public:
  virtual ~WsPeer() = default;
  virtual void kick() = 0;                              // the queue has something: write if idle
  virtual void close_slow(const std::string& why) = 0;  // close with 1008
};

struct WsClient {
  std::uint64_t id = 0;
  std::string client_id;  // the X-Client-Id / client_id it gave
  std::weak_ptr<WsPeer> peer;
  ClientQueue queue;
  std::set<std::string> machines;
  bool all_machines = false;
  explicit WsClient(std::size_t max) : queue(max) {}
  bool wants(const std::string& m) const { return all_machines || machines.count(m); }
};

class WsHub {
 public:
  explicit WsHub(std::size_t max_clients, std::size_t queue_messages)
      : max_clients_(max_clients), queue_messages_(queue_messages) {}
  // Null when the cap is reached.
  std::shared_ptr<WsClient> add(std::string client_id, std::weak_ptr<WsPeer> peer);
  void remove(std::uint64_t id);
  std::size_t size() const { return clients_.size(); }
  bool full() const { return clients_.size() >= max_clients_; }
  // Number of open sockets of one client id.
  std::size_t count(const std::string& client_id) const;

  void publish_status(const std::string& machine, const Frame& f);
  void publish(const std::string& machine, const Frame& f);  // to the machine's subscribers
  void broadcast(const Frame& f);                            // to everyone
  void send(WsClient& c, Frame f);

  static Frame frame(std::string s) { return std::make_shared<const std::string>(std::move(s)); }

 private:
  void deliver(WsClient& c, Frame f, const std::string* status_machine);
  std::size_t max_clients_, queue_messages_;
  std::uint64_t next_id_ = 1;
  std::map<std::uint64_t, std::shared_ptr<WsClient>> clients_;
};

}  // namespace cncstream::daemon
