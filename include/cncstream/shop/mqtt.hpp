#pragma once
// A machine's live telemetry over MQTT (Mosquitto's client library), for
// the tools shops already use (docs/shop.md). Topics under
// cncstream/<shop>/<machine>/:
//   availability  retained, AVAILABLE; UNAVAILABLE as the client's last will
//                 (the daemon vanished) or when it stops
//   state         retained, the MTConnect-named state (JSON), on each change
//   events        QoS 1, the outbox's events in order (JSON with "seq"), from
//                 where the last acknowledged one left off (at least once)
// One client per machine (each its own last will), reconnecting by itself;
// on every connection the availability and the state are published again,
// so a broker restart (which forgets retained messages without persistence)
// loses nothing that matters.
#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>

#include "cncstream/shop/machine_state.hpp"
#include "cncstream/shop/outbox.hpp"

struct mosquitto;

namespace cncstream::shop {

struct MqttSettings {
  std::string host = "127.0.0.1";
  int port = 1883;
  std::string username, password;  // "" : none
  std::string ca_file;             // TLS when set (the broker's CA)
  std::string shop = "shop";
  int keepalive_s = 10;            // at least 5; the will fires about 1.5 x this after the daemon vanished
};

// The topic for a machine's item ("availability", "state", "events").
std::string mqtt_topic(const MqttSettings& s, const std::string& machine, const std::string& item);

class MqttMachine {
 public:
  // Starts connecting at once (its own network thread); throws ShopError for bad settings.
  MqttMachine(const MqttSettings& settings, std::string machine, Outbox& outbox);
  ~MqttMachine();  // publishes UNAVAILABLE, disconnects
  MqttMachine(const MqttMachine&) = delete;
  MqttMachine& operator=(const MqttMachine&) = delete;

  void state(const MachineState& s);  // any thread
  void pump();                        // publish new outbox events (any thread)
  bool connected() const { return connected_; }

 private:
  static void on_connect(mosquitto*, void* self, int rc);
  static void on_disconnect(mosquitto*, void* self, int rc);
  static void on_publish(mosquitto*, void* self, int mid);
  void publish_retained(const std::string& item, const std::string& payload);

  MqttSettings settings_;
  std::string machine_;
  Outbox& outbox_;
  mosquitto* m_ = nullptr;
  std::atomic<bool> connected_{false};
  std::mutex mu_;
  std::string state_json_;
  std::int64_t published_up_to_ = 0;     // events handed to the client
  std::map<int, std::int64_t> inflight_;  // mid -> seq
  std::map<std::int64_t, bool> pending_;  // seq -> acknowledged
};

}  // namespace cncstream::shop
