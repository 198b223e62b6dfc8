#pragma once
// A daemon's membership of a shop: for each of its machines a reporter
// (session events -> MTConnect state -> the outbox), and one thread of its
// own that speaks to the hub (libpq, blocking, off the event loop): it
// ships the outbox in order, sends heartbeats (which renew the leases), and
// claims a job for a machine that is free. A hub that is down only pauses
// shipping and claiming; the machines and the local queue go on.
#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <atomic>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <set>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "cncstream/session/machine_session.hpp"
#include "cncstream/shop/hub.hpp"
#include "cncstream/shop/machine_state.hpp"
#include "cncstream/shop/mqtt.hpp"
#include "cncstream/shop/outbox.hpp"

namespace cncstream::shop {

struct ShopSettings {
  std::string url;           // postgresql://PC_USER@HUB/DB
  std::string name = "shop"; // the shop's name (MQTT topics)
  std::string pc;            // this PC's name ("" : the host name)
  double lease_s = 30;       // a job's lease; renewed every heartbeat_s
  double heartbeat_s = 5;
  double retry_s = 2;        // reconnecting to a hub that is down
  double progress_s = 1;     // at most one line-progress event per machine this often
  // A hub not heard from for hub_check_s is asked (SELECT 1); an answer that
  // takes longer than hub_timeout_s (any call) means it is gone, though its
  // connection never closed: claiming pauses and the thread connects again.
  double hub_check_s = 1;
  double hub_timeout_s = 3;
  std::optional<MqttSettings> mqtt;  // live telemetry to a broker (none: no MQTT)
};

struct ShopMachine {
  std::string name;
  std::vector<std::string> capabilities;
  bool claim = true;  // takes jobs from the shop's queue when free
  session::MachineSession* session = nullptr;
};

// What the shop asks of the daemon, on the daemon's event loop thread.
class LocalJobs {
 public:
  virtual ~LocalJobs() = default;
  // Connected, not in alarm, nothing unfinished in its local queue.
  virtual bool free_for_shop_job(const std::string& machine) = 0;
  // Creates the local job (never started by itself); returns its id;
  // throws std::exception with the reason it cannot. A job requeued on this
  // machine (job.resume_after_line > 0) is queued as a resume after that
  // line; `earlier_local` is the local job that ran it here before (0: none).
  virtual std::int64_t add_shop_job(const std::string& machine, const ClaimedJob& job, std::int64_t earlier_local) = 0;
  // The hub cancelled the shop job this local job holds: drop it if it has
  // not started (a started one is the operator's to stop).
  virtual void shop_job_cancelled(std::int64_t local_id) = 0;
};

class ShopClient {
 public:
  ShopClient(boost::asio::io_context& io, ShopSettings settings, std::vector<ShopMachine> machines,
             const std::filesystem::path& journal, LocalJobs& local);
  ~ShopClient();  // stops the thread; call on the event loop thread (or after it stopped)
  ShopClient(const ShopClient&) = delete;
  ShopClient& operator=(const ShopClient&) = delete;

  // A local job changed state (the daemon's hook, on the event loop): a shop
  // job's change goes to the outbox.
  void job_state(std::int64_t local_id, const std::string& machine, const std::string& state, long last_line,
                 const std::string& message, const std::string& file_name);

  bool hub_up() const { return hub_up_; }
  bool mqtt_connected(const std::string& machine) const;
  std::int64_t unsent() const { return outbox_.unsent_count(); }
  // The machine's state as last derived (any thread).
  MachineState state(const std::string& machine) const;
  void set_claiming(const std::string& machine, bool on);  // event loop thread
  const ShopSettings& settings() const { return settings_; }

  // Observers of the state each machine reports (MQTT, SHDR); called on the event loop.
  using StateListener = std::function<void(const std::string& machine, const MachineState&)>;
  void on_state(StateListener l) { state_listeners_.push_back(std::move(l)); }

 private:
  struct Reporter;
  void on_session_event(Reporter& r, const session::SessionEvent& e);
  void refresh(Reporter& r, bool force_event);
  void append(const std::string& machine, const std::string& kind, std::int64_t shop_job, const std::string& body);
  void tick();
  void worker();
  void wake();
  void serve(Hub& hub);

  boost::asio::io_context& io_;
  ShopSettings settings_;
  LocalJobs& local_;
  Outbox outbox_;
  std::set<std::int64_t> cancelled_seen_;  // shop jobs whose cancellation was handled (event loop)
  std::vector<std::unique_ptr<Reporter>> reporters_;
  std::map<std::string, std::unique_ptr<MqttMachine>> mqtt_;
  std::vector<StateListener> state_listeners_;
  boost::asio::steady_timer timer_;
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);

  // Shared with the worker thread.
  mutable std::mutex mu_;
  std::condition_variable cv_;
  bool stop_ = false;
  bool woken_ = false;
  std::deque<std::string> claim_requests_;
  std::map<std::string, MachineState> states_;
  std::map<std::string, MachineInfo> infos_;
  std::atomic<bool> hub_up_{false};
  std::thread thread_;
  // The worker's own: when the next heartbeats are due.
  double next_heartbeat_ = 0;
  double last_talk_ = 0;  // when the hub last answered
  std::set<std::int64_t> received_;  // shop jobs whose claim this process received
  std::set<std::int64_t> released_;  // shop jobs assigned here whose claim never arrived, released
  bool registered_ = false;
  // A claimed job being added (event loop only): its state changes belong to it.
  std::optional<std::pair<std::string, std::int64_t>> adding_;
};

}  // namespace cncstream::shop
