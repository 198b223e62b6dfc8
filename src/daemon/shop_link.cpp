#include "cncstream/daemon/shop_link.hpp"

#include <spdlog/spdlog.h>

#include <fstream>

#include "cncstream/daemon/file_store.hpp"
#include "cncstream/daemon/job_manager.hpp"
#include "cncstream/daemon/machines.hpp"

namespace cncstream::daemon {

ShopLink::ShopLink(boost::asio::io_context& io, const DaemonConfig& config, FileStore& files, Machines& machines,
                   JobManager& jobs)
    : files_(files), machines_(machines), jobs_(jobs) {
  shop::ShopSettings s;
  s.url = config.shop.url;
  s.name = config.shop.name;
  s.pc = config.shop.pc;
  s.lease_s = config.shop.lease_s;
  s.heartbeat_s = config.shop.heartbeat_s;
  if (!config.shop.mqtt_host.empty()) {
    shop::MqttSettings mq;
    mq.host = config.shop.mqtt_host;
    mq.port = config.shop.mqtt_port;
    mq.username = config.shop.mqtt_username;
    mq.password = config.shop.mqtt_password;
    mq.ca_file = config.shop.mqtt_ca_file;
    mq.keepalive_s = static_cast<int>(config.shop.mqtt_keepalive_s);
    s.mqtt = mq;
  }
  std::vector<shop::ShopMachine> ms;
  for (const auto& m : machines.all()) {
    shop::ShopMachine sm;
    sm.name = m->config.name;
    sm.capabilities = m->config.capabilities;
    sm.claim = m->config.shop_claim;
    sm.session = m->session.get();
    ms.push_back(std::move(sm));
  }
  if (config.shop.mtconnect_port) {
    unsigned short port = *config.shop.mtconnect_port;
    for (const auto& m : ms) {
      adapters_.push_back(std::make_unique<shop::ShdrAdapter>(io, config.shop.mtconnect_address, port, m.name));
      spdlog::info("machine {}: MTConnect adapter (SHDR) on {}:{}", m.name, config.shop.mtconnect_address,
                   adapters_.back()->port());
      if (port) ++port;
    }
  }
  client_ = std::make_unique<shop::ShopClient>(io, s, std::move(ms), journal_path(config), *this);
  view_ = std::make_unique<shop::ShopViewReader>(config.shop.url);
  for (auto& a : adapters_)
    client_->on_state([a = a.get()](const std::string& machine, const shop::MachineState& st) {
      if (machine == a->machine()) a->update(st);
    });
  jobs_.on_state_change = [this](const DaemonJob& j) {
    client_->job_state(j.row.id, j.row.machine, j.row.state, static_cast<long>(j.row.last_line), j.row.message,
                       j.row.file_name);
  };
  // Jobs this daemon found running when it started again (it had died
  // under them): the hub hears they were interrupted, with their last line,
  // rather than a lease its heartbeats would renew for ever.
  for (const auto id : jobs_.interrupted_at_recovery()) {
    try {
      jobs_.on_state_change(jobs_.get(id));
    } catch (const ApiError&) {
    }
  }
}

ShopLink::~ShopLink() {
  jobs_.on_state_change = nullptr;
  view_.reset();
  client_.reset();
  adapters_.clear();
}

unsigned short ShopLink::mtconnect_port(const std::string& machine) const {
  for (const auto& a : adapters_)
    if (a->machine() == machine) return a->port();
  return 0;
}

bool ShopLink::free_for_shop_job(const std::string& machine) {
  Machine* m = machines_.find(machine);
  if (!m || !m->session->ready() || m->session->in_alarm() || m->session->job_active()) return false;
  return !jobs_.has_unfinished(machine);
}

std::int64_t ShopLink::add_shop_job(const std::string& machine, const shop::ClaimedJob& job, std::int64_t earlier_local) {
  const auto temp = files_.temp_path();
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    out.write(job.content.data(), static_cast<std::streamsize>(job.content.size()));
    if (!out) throw std::runtime_error(temp.string() + ": cannot write the shop job's file");
  }
  try {
    const auto [info, fresh] = files_.ingest(temp, job.file_name);
    nlohmann::json body = {{"machine", machine}, {"file", info.id}};
    if (!job.params_json.empty()) body["params"] = nlohmann::json::parse(job.params_json);
    std::optional<ShopResume> resume;
    if (job.resume_after_line > 0) resume = ShopResume{job.resume_after_line, earlier_local};
    const auto created = jobs_.create(body, resume);
    return created.at("id").get<std::int64_t>();
  } catch (const ApiError& e) {
    throw std::runtime_error(e.message);
  } catch (const FileStoreError& e) {
    throw std::runtime_error(e.what());
  }
}

void ShopLink::shop_job_cancelled(std::int64_t local_id) {
  try {
    if (jobs_.cancel_for_shop(local_id)) spdlog::info("job {}: cancelled on the shop's hub; taken off the local queue", local_id);
  } catch (const ApiError&) {
    // No such local job any more (removed): nothing to drop.
  }
}

}  // namespace cncstream::daemon
