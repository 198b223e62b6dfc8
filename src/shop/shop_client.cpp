#include "cncstream/shop/shop_client.hpp"

#include <boost/asio/post.hpp>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <unistd.h>

#include <chrono>

namespace cncstream::shop {

namespace detail_shop_client {

std::string host_name() {
  char buf[256] = {};
  if (::gethostname(buf, sizeof buf - 1) != 0) return "pc";
  return buf;
}

double steady_now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace detail_shop_client

using detail_shop_client::steady_now;

struct ShopClient::Reporter {
  ShopMachine machine;
  session::Subscription sub;
  MachineState last;             // as last sent to the outbox
  bool sent_any = false;
  std::string program;           // the running (or loaded) job's file name
  std::int64_t shop_job = 0;     // the shop job running now (0: none)
  std::string alarm;
  long last_progress_line = 0;
  double last_progress_at = -1e9;
  bool claim_in_flight = false;
};

ShopClient::ShopClient(boost::asio::io_context& io, ShopSettings settings, std::vector<ShopMachine> machines,
                       const std::filesystem::path& journal, LocalJobs& local)
    : io_(io), settings_(std::move(settings)), local_(local), outbox_(journal), timer_(io) {
  if (settings_.pc.empty()) settings_.pc = detail_shop_client::host_name();
  for (auto& m : machines) {
    auto r = std::make_unique<Reporter>();
    r->machine = std::move(m);
    MachineInfo info;
    info.name = r->machine.name;
    info.pc = settings_.pc;
    info.capabilities = r->machine.capabilities;
    infos_[info.name] = info;
    states_[info.name] = MachineState{};
    Reporter* raw = r.get();
    if (raw->machine.session)
      raw->sub = raw->machine.session->subscribe([this, raw](const session::SessionEvent& e) { on_session_event(*raw, e); });
    if (settings_.mqtt) {
      auto mq = settings_.mqtt;
      mq->shop = settings_.name;
      mqtt_[raw->machine.name] = std::make_unique<MqttMachine>(*mq, raw->machine.name, outbox_);
    }
    reporters_.push_back(std::move(r));
  }
  thread_ = std::thread([this] { worker(); });
  tick();
}

ShopClient::~ShopClient() {
  *alive_ = false;
  mqtt_.clear();
  timer_.cancel();
  {
    std::lock_guard lock(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

MachineState ShopClient::state(const std::string& machine) const {
  std::lock_guard lock(mu_);
  const auto it = states_.find(machine);
  return it == states_.end() ? MachineState{} : it->second;
}

bool ShopClient::mqtt_connected(const std::string& machine) const {
  const auto it = mqtt_.find(machine);
  return it != mqtt_.end() && it->second->connected();
}

void ShopClient::set_claiming(const std::string& machine, bool on) {
  for (auto& r : reporters_)
    if (r->machine.name == machine) r->machine.claim = on;
}

void ShopClient::wake() {
  {
    std::lock_guard lock(mu_);
    woken_ = true;
  }
  cv_.notify_all();
}

void ShopClient::append(const std::string& machine, const std::string& kind, std::int64_t shop_job,
                        const std::string& body) {
  try {
    outbox_.append(machine, kind, shop_job, body);
  } catch (const std::exception& e) {
    spdlog::error("shop: {}", e.what());
    return;
  }
  if (const auto it = mqtt_.find(machine); it != mqtt_.end()) it->second->pump();
  wake();
}

void ShopClient::on_session_event(Reporter& r, const session::SessionEvent& e) {
  using session::SessionEventKind;
  switch (e.kind) {
    case SessionEventKind::Link: refresh(r, false); return;
    case SessionEventKind::Settings: {
      const auto& s = r.machine.session->settings();
      const auto a = s.find(130), b = s.find(131), c = s.find(132);
      if (a != s.end() && b != s.end() && c != s.end()) {
        std::lock_guard lock(mu_);
        infos_[r.machine.name].travel_mm = std::array<double, 3>{a->second, b->second, c->second};
      }
      return;
    }
    case SessionEventKind::JobStarted:
    case SessionEventKind::JobEnded: refresh(r, false); return;
    case SessionEventKind::Controller:
      if (e.controller.kind == protocol::EventKind::Alarm) r.alarm = e.controller.text;
      refresh(r, false);
      return;
    default: return;
  }
}

void ShopClient::refresh(Reporter& r, bool force_event) {
  const auto snap = r.machine.session->snapshot();
  if (!snap.alarm) r.alarm.clear();
  MachineState s = derive_machine_state(snap, r.program, r.alarm);
  {
    std::lock_guard lock(mu_);
    states_[r.machine.name] = s;
  }
  if (force_event || !r.sent_any || !s.same_event_fields(r.last)) {
    r.last = s;
    r.sent_any = true;
    append(r.machine.name, "state", r.shop_job, s.to_json());
  }
  if (const auto it = mqtt_.find(r.machine.name); it != mqtt_.end()) it->second->state(s);
  for (auto& l : state_listeners_) l(r.machine.name, s);
  // The line a job has reached, at most every progress_s (the job's own
  // events carry the exact last line when it ends).
  if (snap.job_active && s.line != r.last_progress_line) {
    const double now = steady_now();
    if (now - r.last_progress_at >= settings_.progress_s) {
      r.last_progress_at = now;
      r.last_progress_line = s.line;
      append(r.machine.name, "progress", r.shop_job, nlohmann::json{{"line", s.line}}.dump());
    }
  }
}

void ShopClient::job_state(std::int64_t local_id, const std::string& machine, const std::string& state, long last_line,
                           const std::string& message, const std::string& file_name) {
  Reporter* r = nullptr;
  for (auto& x : reporters_)
    if (x->machine.name == machine) r = x.get();
  if (!r) return;
  std::optional<std::int64_t> shop_id;
  try {
    shop_id = outbox_.shop_job_of(local_id);
    if (!shop_id && adding_ && adding_->first == machine) {
      outbox_.link_job(local_id, adding_->second, machine);
      shop_id = adding_->second;
    }
  } catch (const std::exception& e) {
    spdlog::error("shop: {}", e.what());
  }
  const bool live = state == "running" || state == "held";
  r->program = live || state == "ready" ? file_name : std::string();
  if (live) r->shop_job = shop_id.value_or(0);
  else if (r->shop_job && shop_id && *shop_id == r->shop_job) r->shop_job = 0;
  if (shop_id)
    append(machine, "job", *shop_id,
           nlohmann::json{{"state", state}, {"last_line", last_line}, {"message", message}, {"local_job", local_id}}.dump());
  refresh(*r, false);
}

// Every 0.2 s on the event loop: which machines would take a job now.
void ShopClient::tick() {
  if (hub_up_) {
    std::vector<std::string> asks;
    for (auto& r : reporters_) {
      if (!r->machine.claim || r->claim_in_flight || adding_) continue;
      bool free = false;
      try {
        free = local_.free_for_shop_job(r->machine.name);
      } catch (const std::exception&) {
      }
      if (!free) continue;
      r->claim_in_flight = true;
      asks.push_back(r->machine.name);
    }
    if (!asks.empty()) {
      {
        std::lock_guard lock(mu_);
        for (auto& a : asks) claim_requests_.push_back(a);
        woken_ = true;
      }
      cv_.notify_all();
    }
  }
  timer_.expires_after(std::chrono::milliseconds(200));
  timer_.async_wait([this, alive = alive_](const boost::system::error_code& ec) {
    if (!ec && *alive) tick();
  });
}

void ShopClient::worker() {
  double next_connect = 0;
  bool said_down = false;
  std::unique_ptr<PgConnection> db;
  while (true) {
    {
      std::unique_lock lock(mu_);
      if (stop_) break;
    }
    if (!db && steady_now() >= next_connect) {
      try {
        db = std::make_unique<PgConnection>(settings_.url, settings_.hub_timeout_s);
        spdlog::info("shop: connected to the hub {}", redact_url(settings_.url));
        said_down = false;
      } catch (const std::exception& e) {
        if (!said_down) spdlog::warn("shop: {} (claiming paused; events wait in the journal)", e.what());
        said_down = true;
        next_connect = steady_now() + settings_.retry_s;
      }
    }
    if (db) {
      try {
        Hub hub(*db);
        serve(hub);
        hub_up_ = true;
      } catch (const std::exception& e) {
        spdlog::warn("shop: the hub failed: {} (claiming paused; events wait in the journal)", e.what());
        said_down = true;
        db.reset();
        registered_ = false;  // a fresh connection sends its heartbeats first
        hub_up_ = false;
        next_connect = steady_now() + settings_.retry_s;
        // Claims asked for and not made: the machines may ask again once it is back.
        std::deque<std::string> dropped;
        {
          std::lock_guard lock(mu_);
          dropped.swap(claim_requests_);
        }
        boost::asio::post(io_, [this, dropped, alive = alive_] {
          if (!*alive) return;
          for (auto& r : reporters_)
            for (const auto& d : dropped)
              if (r->machine.name == d) r->claim_in_flight = false;
        });
      }
    } else {
      hub_up_ = false;
    }
    std::unique_lock lock(mu_);
    cv_.wait_for(lock, std::chrono::milliseconds(200), [this] { return stop_ || woken_; });
    woken_ = false;
  }
  hub_up_ = false;
}

// One round with the hub (the worker's thread): heartbeats when due (they
// register the machines first), the outbox, then the claims asked for.
void ShopClient::serve(Hub& hub) {
  bool talked = false;
  if (!registered_ || steady_now() >= next_heartbeat_) {
    talked = true;
    std::vector<std::pair<MachineInfo, MachineState>> beats;
    {
      std::lock_guard lock(mu_);
      for (const auto& [name, info] : infos_) beats.emplace_back(info, states_[name]);
    }
    std::vector<std::int64_t> cancelled;
    std::vector<std::pair<std::string, std::int64_t>> unknown;  // assigned here, never received
    for (const auto& [info, st] : beats)
      for (const auto& j : hub.heartbeat(info, st, settings_.lease_s)) {
        if (j.status == "cancelled") cancelled.push_back(j.id);
        if (j.status == "assigned" && !received_.count(j.id) && !released_.count(j.id))
          unknown.emplace_back(info.name, j.id);
      }
    // A claim the hub committed whose answer never came (it fell silent, the
    // call timed out): released through the outbox, back to the queue,
    // unless this daemon holds it after all (an earlier run's claim).
    for (const auto& [machine, id] : unknown) {
      released_.insert(id);
      boost::asio::post(io_, [this, machine = machine, id = id, alive = alive_] {
        if (!*alive) return;
        try {
          if (outbox_.local_job_of(id)) return;
        } catch (const std::exception& e) {
          spdlog::warn("shop: {}", e.what());
          return;
        }
        spdlog::warn("shop: shop job {} is assigned to {} but its claim never arrived; released to the queue", id, machine);
        append(machine, "job", id,
               nlohmann::json{{"state", "released"},
                              {"message", "its claim's answer never reached " + machine + " (the hub did not answer in time); "
                                          "back in the queue"}}.dump());
      });
    }
    registered_ = true;
    // Jobs cancelled on the hub (the shop view, an operator) after this PC
    // claimed them leave the local queue; each once.
    if (!cancelled.empty())
      boost::asio::post(io_, [this, cancelled, alive = alive_] {
        if (!*alive) return;
        for (const auto id : cancelled) {
          if (!cancelled_seen_.insert(id).second) continue;
          try {
            if (const auto local = outbox_.local_job_of(id)) local_.shop_job_cancelled(*local);
          } catch (const std::exception& e) {
            spdlog::warn("shop: shop job {} was cancelled on the hub: {}", id, e.what());
          }
        }
      });
    next_heartbeat_ = steady_now() + settings_.heartbeat_s;
  }
  for (const auto& machine : outbox_.machines_with_unsent()) {
    while (true) {
      const auto batch = outbox_.unsent(machine, 500);
      if (batch.empty()) break;
      hub.report_events(machine, batch);  // committed when it returns
      talked = true;
      outbox_.mark_sent(machine, batch.back().seq);
      if (batch.size() < 500) break;
    }
  }
  while (true) {
    std::string machine;
    {
      std::lock_guard lock(mu_);
      if (claim_requests_.empty()) break;
      machine = claim_requests_.front();
      claim_requests_.pop_front();
    }
    std::optional<ClaimedJob> job;
    try {
      job = hub.claim_job(machine, settings_.lease_s);
    } catch (...) {
      // Not claimed: back with the asks the failure hands back (worker()).
      std::lock_guard lock(mu_);
      claim_requests_.push_front(machine);
      throw;
    }
    talked = true;
    if (job) received_.insert(job->id);
    boost::asio::post(io_, [this, machine, job = std::move(job), alive = alive_]() mutable {
      if (!*alive) return;
      Reporter* r = nullptr;
      for (auto& x : reporters_)
        if (x->machine.name == machine) r = x.get();
      if (r) r->claim_in_flight = false;
      if (!job) return;
      if (job->resume_after_line > 0)
        spdlog::info("shop: machine {} claimed shop job {} ({}) to resume after line {}; it waits for the operator",
                     machine, job->id, job->file_name, job->resume_after_line);
      else
        spdlog::info("shop: machine {} claimed shop job {} ({}); it waits for the operator", machine, job->id,
                     job->file_name);
      adding_ = std::make_pair(machine, job->id);
      try {
        std::int64_t earlier = 0;
        if (job->resume_after_line > 0) earlier = outbox_.local_job_of(job->id).value_or(0);
        const auto local_id = local_.add_shop_job(machine, *job, earlier);
        outbox_.link_job(local_id, job->id, machine);
      } catch (const std::exception& e) {
        spdlog::warn("shop: shop job {} cannot be added on {}: {}", job->id, machine, e.what());
        append(machine, "job", job->id, nlohmann::json{{"state", "failed"}, {"message", e.what()}}.dump());
      }
      adding_.reset();
    });
  }
  // A quiet hub is asked, so one that vanished is noticed within
  // hub_check_s + hub_timeout_s even with nothing to send.
  if (!talked && steady_now() - last_talk_ >= settings_.hub_check_s) {
    hub.ping();
    talked = true;
  }
  if (talked) last_talk_ = steady_now();
}

}  // namespace cncstream::shop
