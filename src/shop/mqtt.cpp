#include "cncstream/shop/mqtt.hpp"

#include <mosquitto.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>

namespace cncstream::shop {

namespace detail_mqtt {

constexpr const char* kConsumer = "mqtt";

// libmosquitto's global set-up, once per process.
void init_library() {
  static const int once = [] { return mosquitto_lib_init(); }();
  (void)once;
}

}  // namespace detail_mqtt

std::string mqtt_topic(const MqttSettings& s, const std::string& machine, const std::string& item) {
  return "cncstream/" + s.shop + "/" + machine + "/" + item;
}

MqttMachine::MqttMachine(const MqttSettings& settings, std::string machine, Outbox& outbox)
    : settings_(settings), machine_(std::move(machine)), outbox_(outbox) {
  detail_mqtt::init_library();
  const std::string id = "cncstream-" + settings_.shop + "-" + machine_;
  m_ = mosquitto_new(id.c_str(), true, this);
  if (!m_) throw ShopError("MQTT: cannot create a client for machine " + machine_);
  const auto fail = [&](const std::string& what, int rc) {
    const std::string msg = "MQTT " + settings_.host + ":" + std::to_string(settings_.port) + ": " + what + ": " +
                            mosquitto_strerror(rc);
    mosquitto_destroy(m_);
    m_ = nullptr;
    throw ShopError(msg);
  };
  const std::string will = mqtt_topic(settings_, machine_, "availability");
  if (int rc = mosquitto_will_set(m_, will.c_str(), 11, "UNAVAILABLE", 1, true); rc != MOSQ_ERR_SUCCESS)
    fail("last will", rc);
  if (!settings_.username.empty())
    if (int rc = mosquitto_username_pw_set(m_, settings_.username.c_str(),
                                           settings_.password.empty() ? nullptr : settings_.password.c_str());
        rc != MOSQ_ERR_SUCCESS)
      fail("user name", rc);
  if (!settings_.ca_file.empty())
    if (int rc = mosquitto_tls_set(m_, settings_.ca_file.c_str(), nullptr, nullptr, nullptr, nullptr);
        rc != MOSQ_ERR_SUCCESS)
      fail("TLS (" + settings_.ca_file + ")", rc);
  mosquitto_connect_callback_set(m_, &MqttMachine::on_connect);
  mosquitto_disconnect_callback_set(m_, &MqttMachine::on_disconnect);
  mosquitto_publish_callback_set(m_, &MqttMachine::on_publish);
  mosquitto_reconnect_delay_set(m_, 1, 2, false);
  published_up_to_ = outbox_.cursor(detail_mqtt::kConsumer, machine_);
  // A broker that is not there yet is tried again by the network thread.
  // libmosquitto refuses a keepalive under 5 s.
  const int rc = mosquitto_connect_async(m_, settings_.host.c_str(), settings_.port, std::max(5, settings_.keepalive_s));
  if (rc != MOSQ_ERR_SUCCESS && rc != MOSQ_ERR_ERRNO) fail("connect", rc);
  if (int r = mosquitto_loop_start(m_); r != MOSQ_ERR_SUCCESS) fail("network thread", r);
}

MqttMachine::~MqttMachine() {
  if (!m_) return;
  if (connected_) {
    int mid = 0;
    mosquitto_publish(m_, &mid, mqtt_topic(settings_, machine_, "availability").c_str(), 11, "UNAVAILABLE", 1, true);
  }
  mosquitto_disconnect(m_);
  mosquitto_loop_stop(m_, true);
  mosquitto_destroy(m_);
}

void MqttMachine::publish_retained(const std::string& item, const std::string& payload) {
  mosquitto_publish(m_, nullptr, mqtt_topic(settings_, machine_, item).c_str(), static_cast<int>(payload.size()),
                    payload.data(), 1, true);
}

void MqttMachine::on_connect(mosquitto*, void* self, int rc) {
  auto* me = static_cast<MqttMachine*>(self);
  if (rc != 0) {
    spdlog::warn("MQTT ({}): the broker refused the connection: {}", me->machine_, mosquitto_connack_string(rc));
    return;
  }
  me->connected_ = true;
  std::string st;
  {
    std::lock_guard lock(me->mu_);
    st = me->state_json_;
    // What was handed over but not acknowledged goes again (at least once).
    me->inflight_.clear();
    me->pending_.clear();
    me->published_up_to_ = me->outbox_.cursor(detail_mqtt::kConsumer, me->machine_);
  }
  me->publish_retained("availability", "AVAILABLE");
  if (!st.empty()) me->publish_retained("state", st);
  me->pump();
}

void MqttMachine::on_disconnect(mosquitto*, void* self, int) { static_cast<MqttMachine*>(self)->connected_ = false; }

void MqttMachine::on_publish(mosquitto*, void* self, int mid) {
  auto* me = static_cast<MqttMachine*>(self);
  std::lock_guard lock(me->mu_);
  const auto it = me->inflight_.find(mid);
  if (it == me->inflight_.end()) return;  // a state or availability message
  me->pending_[it->second] = true;
  me->inflight_.erase(it);
  // The cursor moves over every acknowledged event up to the first that is not.
  std::int64_t upto = -1;
  while (!me->pending_.empty() && me->pending_.begin()->second) {
    upto = me->pending_.begin()->first;
    me->pending_.erase(me->pending_.begin());
  }
  if (upto >= 0) {
    try {
      me->outbox_.set_cursor(detail_mqtt::kConsumer, me->machine_, upto);
    } catch (const std::exception& e) {
      spdlog::error("MQTT ({}): {}", me->machine_, e.what());
    }
  }
}

void MqttMachine::state(const MachineState& s) {
  const std::string j = s.to_json();
  {
    std::lock_guard lock(mu_);
    if (j == state_json_) return;
    state_json_ = j;
  }
  if (connected_) publish_retained("state", j);
}

void MqttMachine::pump() {
  if (!connected_) return;
  std::lock_guard lock(mu_);
  // A bounded window: the broker's own queue limits are not ours to fill.
  while (inflight_.size() < 200) {
    std::vector<OutboxEvent> events;
    try {
      events = outbox_.after(machine_, published_up_to_, 50);
    } catch (const std::exception& e) {
      spdlog::error("MQTT ({}): {}", machine_, e.what());
      return;
    }
    if (events.empty()) return;
    for (const auto& e : events) {
      nlohmann::json body;
      try {
        body = nlohmann::json::parse(e.body_json);
      } catch (const nlohmann::json::exception&) {
        body = e.body_json;
      }
      const std::string payload = nlohmann::json{{"seq", e.seq}, {"at", e.at}, {"kind", e.kind},
                                                 {"job", e.shop_job ? nlohmann::json(e.shop_job) : nlohmann::json(nullptr)},
                                                 {"body", body}}
                                      .dump();
      int mid = 0;
      const int rc = mosquitto_publish(m_, &mid, mqtt_topic(settings_, machine_, "events").c_str(),
                                       static_cast<int>(payload.size()), payload.data(), 1, false);
      if (rc != MOSQ_ERR_SUCCESS) return;  // again after the reconnection
      inflight_[mid] = e.seq;
      pending_[e.seq] = false;
      published_up_to_ = e.seq;
    }
  }
}

}  // namespace cncstream::shop
