#include "cncstream/daemon/machines.hpp"

#include <boost/asio/post.hpp>
#include <spdlog/spdlog.h>

#include <chrono>

#include "cncstream/daemon/http_types.hpp"
#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/protocol/link_model.hpp"
#include "cncstream/protocol/profiles_dir.hpp"
#include "cncstream/transport/port_discovery.hpp"

namespace cncstream::daemon {

using nlohmann::json;

// ---- ports ------------------------------------------------------------------

namespace {

// `port = "auto"`: the one likely controller, chosen again at each connection.
class AutoPort final : public session::MachinePort {
 public:
  std::string path() override {
    std::vector<transport::PortInfo> ports;
    try {
      ports = transport::list_ports();
    } catch (const std::exception&) {
    }
    const auto choice = transport::choose_auto_port(ports);
    if (!choice.port) throw std::runtime_error("port auto: " + choice.message);
    return choice.port->path;
  }
  std::string describe() override { return "auto"; }
};

std::int64_t now_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

json axes3(const std::optional<protocol::Axes>& a) {
  if (!a) return nullptr;
  return json::array({(*a)[0], (*a)[1], (*a)[2]});
}

template <typename T>
json opt(const std::optional<T>& v) {
  if (!v) return nullptr;
  return *v;
}

const char* kind_name(protocol::EventKind k) {
  using protocol::EventKind;
  switch (k) {
    case EventKind::LineError:
    case EventKind::CheckError: return "error";
    case EventKind::Alarm: return "alarm";
    case EventKind::Warning: return "warning";
    case EventKind::Reset: return "reset";
    default: return "info";
  }
}

}  // namespace

json code_info_json(const std::optional<protocol::CodeInfo>& info) {
  if (!info) return nullptr;
  return {{"code", info->code}, {"name", info->name}, {"text", info->text}, {"action", info->action},
          {"reset_required", info->reset_required}, {"position_lost", info->position_lost}};
}

SimMachinePort::SimMachinePort(session::SimulatorOptions base, std::size_t vanish_first_after)
    : base_(std::move(base)), vanish_first_after_(vanish_first_after) {}

std::string SimMachinePort::path() {
  if (!current_ || current_->ended()) {
    session::SimulatorOptions o = base_;
    o.faults.vanish_after = std::exchange(vanish_first_after_, 0);
    current_ = std::make_shared<session::SimulatorPort>(o);
  }
  return current_->path();
}

void SimMachinePort::opened() {
  if (current_) current_->opened();
}

void SimMachinePort::set_next_design(std::optional<geometry::Mesh> design, std::optional<cam::Cutter> cutter,
                                     std::map<int, cam::Cutter> tools, std::optional<geometry::Box3> stock) {
  base_.design = std::move(design);
  base_.cutter = cutter;
  base_.stock = stock;
  base_.tools.reset();
  if (!tools.empty()) base_.tools = cncsim::ToolTable(tools.begin(), tools.end());
}

std::shared_ptr<session::SimulatorPort> SimMachinePort::retire() { return std::exchange(current_, nullptr); }

void SimMachinePort::operator_mount(int tool) {
  if (current_) current_->operator_mount(tool);
}

// ---- machines ---------------------------------------------------------------

gcode::StreamLink machine_link(const MachineConfig& config) {
  if (!config.profile.empty()) {
    try {
      return protocol::link_model(
          protocol::load_firmware_profile(protocol::default_profiles_dir() / (config.profile + ".toml")));
    } catch (const std::exception& e) {
      spdlog::warn("machine {}: profile {}: {}; its programs are planned for {} baud", config.name, config.profile,
                   e.what(), config.baud);
    }
  }
  gcode::StreamLink link = protocol::grbl_default_link();
  link.bytes_per_second = gcode::bytes_per_second_for_baud(config.baud);
  return link;
}

Machines::Machines(boost::asio::io_context& io, boost::asio::thread_pool& pool, const DaemonConfig& config, WsHub& hub,
                   std::filesystem::path journal_path)
    : io_(io), pool_(pool), config_(config), hub_(hub), journal_path_(std::move(journal_path)) {
  for (const auto& mc : config.machines) {
    auto m = std::make_unique<Machine>();
    m->config = mc;
    // The simulator starts with its work zero at machine zero and nothing to
    // hit: its tool changes travel 50 mm above it unless told otherwise.
    if (mc.port == "sim" && !m->config.tool_change.safe_z) m->config.tool_change.safe_z = 50;
    session::MachineOptions o;
    o.name = mc.name;
    if (mc.port == "sim") {
      session::SimulatorOptions so;
      so.speed = mc.sim_speed;
      so.baud = mc.baud;  // the simulator's wire is paced like the board's
      so.settings_file = mc.sim_settings;
      so.resolution = mc.sim_resolution;
      so.tolerance = mc.sim_tolerance;
      session::parse_sim_speed(so.speed);  // a bad speed fails at start, naming it
      try {
        if (!mc.sim_tool_table.empty()) so.stick_outs = session::parse_sim_stick_outs(mc.sim_tool_table);
        so.tool_sensor = mc.sim_tool_sensor;
        if (!so.tool_sensor.empty()) session::check_sim_tool_sensor(so.tool_sensor);  // checked at start
      } catch (const std::exception& e) {
        throw std::invalid_argument(cat({"machine '", mc.name, "': ", e.what()}));
      }
      so.probe_surface_z = mc.sim_probe_surface_z;
      m->sim = std::make_shared<SimMachinePort>(so, mc.sim_vanish_after);
      o.port = m->sim;
    } else if (mc.port == "auto") {
      o.port = std::make_shared<AutoPort>();
    } else {
      o.port = std::make_shared<session::DevicePort>(mc.port);
    }
    o.serial = transport::parse_serial_settings(std::to_string(mc.baud));
    o.profiles_dir = protocol::default_profiles_dir();
    if (!mc.profile.empty()) o.force_profile = mc.profile;
    o.reconnect_interval_s = mc.reconnect_s;
    o.actions.probe_plate_mm = mc.tool_change.plate_thickness;
    // The machine's own routine; each job sets its own before it starts (JobManager::start).
    o.tool_change = routine_config(m->config.tool_change, false);
    m->session = std::make_unique<session::MachineSession>(io, o);
    // The journal subscribes first: when our handler sees JobStarted, its job id is set.
    m->journal = std::make_unique<session::JobJournal>(*m->session, journal_path_, mc.name + ":" + mc.port);
    Machine* raw = m.get();
    m->sub = m->session->subscribe([this, raw](const session::SessionEvent& e) { on_event(*raw, e); });
    machines_.push_back(std::move(m));
  }
}

Machines::~Machines() { *alive_ = false; }

void Machines::open_all() {
  for (auto& m : machines_) try_open(*m);
}

void Machines::try_open(Machine& m) {
  try {
    m.session->open();
    if (m.open_failures) spdlog::info("machine {}: the port is there now", m.config.name);
    m.open_failures = 0;
  } catch (const std::exception& e) {
    if (m.open_failures++ == 0)
      spdlog::warn("machine {}: {} (trying again every {} s)", m.config.name, e.what(), m.config.reconnect_s);
    if (m.session->link() != session::LinkState::Closed) return;  // the session retries by itself
    if (!m.open_retry) m.open_retry = std::make_unique<boost::asio::steady_timer>(io_);
    m.open_retry->expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(m.config.reconnect_s)));
    m.open_retry->async_wait([this, &m, alive = alive_](const boost::system::error_code& ec) {
      if (ec || !*alive || m.session->link() != session::LinkState::Closed) return;
      try_open(m);
    });
  }
}

Machine* Machines::find(const std::string& name) {
  for (auto& m : machines_)
    if (m->config.name == name) return m.get();
  return nullptr;
}

std::vector<std::string> Machines::names() const {
  std::vector<std::string> n;
  for (const auto& m : machines_) n.push_back(m->config.name);
  return n;
}

void Machines::publish(Machine& m, json j) {
  j["machine"] = m.config.name;
  hub_.publish(m.config.name, WsHub::frame(dump_json(j)));
}

std::string Machines::status_frame(Machine& m) {
  const auto& s = *m.session;
  const auto st = s.status();
  json j = {{"type", "status"}, {"machine", m.config.name}, {"seq", ++m.status_seq}, {"link", to_string(s.link())},
            {"alarm", s.in_alarm()}, {"job_active", s.job_active()},
            {"jogging", s.engine() && s.engine()->jogging()},
            {"jog_held", s.engine() && s.engine()->jog().held()}, {"reported_us", now_us()},
            {"tool_change", tool_change(m)}, {"tool_in_spindle", s.snapshot().tool_in_spindle}};
  if (st) {
    j["state"] = protocol::to_string(st->state);
    j["state_text"] = st->state_text;
    j["mpos"] = axes3(st->mpos);
    j["wpos"] = axes3(st->wpos);
    j["wco"] = axes3(st->wco);
    j["feed"] = opt(st->feed);
    j["spindle"] = opt(st->spindle);
    j["overrides"] = opt(st->overrides);
    j["buffer"] = {{"planner_free", opt(st->planner_free)}, {"rx_free", opt(st->rx_free)}};
    j["line"] = opt(st->line_number);
  }
  return dump_json(j);
}

// Progress frames at most 10 per second: the status frames carry the pace.
void Machines::push_progress(const std::string& name, Machine& m) {
  const double now = m.session->now();
  if (now - m.last_progress_push < 0.1 || !m.session->engine() || !listener_.progress) return;
  m.last_progress_push = now;
  listener_.progress(name, m.session->engine()->progress());
}

void Machines::on_event(Machine& m, const session::SessionEvent& e) {
  using session::SessionEventKind;
  const std::string& name = m.config.name;
  switch (e.kind) {
    case SessionEventKind::Link: {
      spdlog::info("machine {}: link {}: {}", name, to_string(e.link), e.text);
      publish(m, {{"type", "link"}, {"link", to_string(e.link)}, {"text", e.text}});
      if (e.link != session::LinkState::Ready) m.jog_ws_client = 0;
      if (m.pending_start && e.link == session::LinkState::Ready) {
        session::JobInput job = std::move(*m.pending_start);
        m.pending_start.reset();
        // Posted: not from inside the session's own event.
        boost::asio::post(io_, [this, &m, job = std::move(job), alive = alive_]() mutable {
          if (!*alive) return;
          const auto r = m.session->start_job(std::move(job));
          if (!r) {
            m.verifying = false;
            if (listener_.start_failed) listener_.start_failed(m.config.name, false, r.reason);
          }
        });
      } else if (m.pending_start && e.link == session::LinkState::Disconnected) {
        m.pending_start.reset();
        m.verifying = false;
        if (listener_.start_failed) listener_.start_failed(name, false, "the simulator did not come up: " + e.text);
      }
      return;
    }
    case SessionEventKind::Log: spdlog::info("machine {}: {}", name, e.text); return;
    case SessionEventKind::Settings:
      publish(m, {{"type", "event"}, {"kind", "info"}, {"code", 0}, {"line", 0}, {"text", e.text}, {"info", nullptr}});
      return;
    case SessionEventKind::JobStarted:
      spdlog::info("machine {}: job started ({} lines, journal job {})", name, e.job ? e.job->lines.size() : 0,
                   m.journal->job_id());
      if (listener_.started) listener_.started(name, m.journal->job_id());
      return;
    case SessionEventKind::JobEnded: {
      spdlog::info("machine {}: job ended: {} ({}), last answered line {}", name, protocol::to_string(e.outcome), e.text,
                   e.last_answered_line);
      if (listener_.ended) listener_.ended(name, e.outcome, e.last_answered_line, e.text);
      if (m.verifying && m.sim) {
        m.verifying = false;
        const bool completed = e.outcome == protocol::JobOutcome::Completed;
        boost::asio::post(io_, [this, &m, completed, alive = alive_] {
          if (!*alive) return;
          m.session->close();
          auto old = m.sim->retire();
          m.sim->set_next_design(std::nullopt, std::nullopt);
          // The verify compares the stock with the design: seconds for a big
          // part, so on the worker pool, never on the event loop.
          boost::asio::post(pool_, [this, &m, old, completed, alive] {
            SimVerifyReport rep;
            if (old) {
              const auto r = old->finish(completed);
              rep.gouged = r.gouged;
              rep.largest_gouge_mm = r.largest_gouge_mm;
              rep.text = r.text;
            }
            boost::asio::post(io_, [this, &m, rep = std::move(rep), alive] {
              if (*alive && listener_.verified) listener_.verified(m.config.name, rep);
            });
          });
          try {
            m.session->open();
          } catch (const std::exception& ex) {
            spdlog::warn("machine {}: {}", m.config.name, ex.what());
          }
        });
      }
      return;
    }
    case SessionEventKind::ToolChange: {
      spdlog::info("machine {}: tool change: {}", name, e.text);
      // The simulator has no hands: its operator mounts the tool the moment
      // the prompt asks for it (a real one mounts, then jogs, zeroes and
      // confirms), whichever front end then answers (page, API, pendant).
      if (m.sim && e.tool_prompt && e.tool_prompt->kind != protocol::PromptKind::Question && e.tool_prompt->tool > 0)
        m.sim->operator_mount(e.tool_prompt->tool);
      publish(m, {{"type", "event"}, {"kind", "tool-change"}, {"code", 0}, {"line", 0}, {"text", e.text}, {"info", nullptr}});
      json f = {{"type", "tool_change"}, {"state", tool_change(m)}, {"text", e.text}, {"record", nullptr}};
      if (const auto& r = e.tool_record)
        f["record"] = {{"line", r->line}, {"tool", r->tool}, {"method", r->skipped ? "skipped" : protocol::to_string(r->method)},
                       {"offset_z", r->offset_z ? json(*r->offset_z) : json(nullptr)},
                       {"length_known", r->length_known}, {"note", r->note}};
      publish(m, std::move(f));
      return;
    }
    case SessionEventKind::Routine: {  // outside a job: corner probing, the outline, the tool routines
      spdlog::info("machine {}: {}", name, e.text);
      // The simulated operator mounts what a tool routine asks for (as at a job's change).
      if (m.sim && e.routine_prompt && e.routine_prompt->tool > 0 &&
          (e.routine_prompt->kind == protocol::PromptKind::MountTool ||
           e.routine_prompt->kind == protocol::PromptKind::ZeroManually))
        m.sim->operator_mount(e.routine_prompt->tool);
      publish(m, {{"type", "event"}, {"kind", "routine"}, {"code", 0}, {"line", 0}, {"text", e.text}, {"info", nullptr}});
      json f = {{"type", "routine"}, {"state", routine(m)}, {"text", e.text},
                {"succeeded", e.routine_succeeded ? json(*e.routine_succeeded) : json(nullptr)},
                {"record", nullptr}, {"tool_reference", tool_reference(m)}};
      if (const auto& r = e.tool_record)
        f["record"] = {{"tool", r->tool}, {"method", r->skipped ? "skipped" : protocol::to_string(r->method)},
                       {"offset_z", r->offset_z ? json(*r->offset_z) : json(nullptr)},
                       {"length_known", r->length_known}, {"note", r->note}};
      publish(m, std::move(f));
      return;
    }
    case SessionEventKind::Controller: break;
  }
  const auto& ev = e.controller;
  using protocol::EventKind;
  switch (ev.kind) {
    case EventKind::Status:
      if (m.session->status() && m.session->status()->state != protocol::MachineState::Alarm) m.last_alarm.reset();
      hub_.publish_status(name, WsHub::frame(status_frame(m)));
      // The executing line moves with the planner (Bf:), not only with answers.
      if (m.session->job_active()) push_progress(name, m);
      if (m.session->job_active() && m.session->status() && m.session->engine() &&
          m.session->engine()->progress().state == protocol::JobState::Running && listener_.holding)
        listener_.holding(name, m.session->status()->state == protocol::MachineState::Hold,
                          m.session->engine()->progress().last_answered_line);
      return;
    case EventKind::LineAnswered: push_progress(name, m); return;
    case EventKind::JobState:
      // The routine begins (or ends): the page shows its panel at once, not at the next status.
      if (m.session->engine() && m.session->engine()->progress().state == protocol::JobState::ToolChange)
        publish(m, {{"type", "tool_change"}, {"state", tool_change(m)}, {"text", ev.text}, {"record", nullptr}});
      if (m.session->engine() && listener_.state) {
        const auto st = m.session->engine()->progress().state;
        if (st == protocol::JobState::Running) listener_.state(name, "running");
        else if (st == protocol::JobState::Paused || st == protocol::JobState::HeldOnError) listener_.state(name, "held");
      }
      return;
    case EventKind::JobFinished: return;
    case EventKind::CommandAnswered:
      publish(m, {{"type", "console"}, {"dir", "in"}, {"text", ev.text}});
      if (ev.info) publish(m, {{"type", "event"}, {"kind", "error"}, {"code", ev.code}, {"line", 0}, {"text", ev.text},
                               {"info", code_info_json(ev.info)}});
      return;
    case EventKind::Alarm:
      m.last_alarm = ev.info;
      spdlog::warn("machine {}: ALARM {}", name, ev.text);
      break;
    case EventKind::LineError: spdlog::warn("machine {}: {}", name, ev.text); break;
    case EventKind::Info: publish(m, {{"type", "console"}, {"dir", "in"}, {"text", ev.text}}); return;
    default: break;
  }
  publish(m, {{"type", "event"}, {"kind", kind_name(ev.kind)}, {"code", ev.code}, {"line", ev.source_line},
              {"text", ev.text}, {"info", code_info_json(ev.info)}});
}

session::CommandResult Machines::start_job(Machine& m, session::JobInput job, std::optional<geometry::Mesh> design,
                                           std::optional<cam::Cutter> cutter, std::map<int, cam::Cutter> tools,
                                           std::optional<geometry::Box3> stock) {
  if (!(m.sim && m.config.sim_verify && design && cutter)) return m.session->start_job(std::move(job));
  auto& s = *m.session;
  if (!s.ready()) return session::CommandResult::refused(cat({"the machine is not connected (", to_string(s.link()), ")"}));
  if (s.job_active()) return session::CommandResult::refused("a job is running");
  if (s.in_alarm()) return session::CommandResult::refused("the controller is in alarm: unlock or home first");
  if (m.pending_start) return session::CommandResult::refused("a job is being started");
  // A verified simulation cuts a fresh stock: the simulator is restarted
  // with the part as its design, and the job starts when it answers.
  if (auto r = s.close(); !r) return r;
  auto old = m.sim->retire();
  boost::asio::post(pool_, [old] {});  // its thread is joined off the event loop
  m.sim->set_next_design(std::move(design), cutter, std::move(tools), stock);
  m.pending_start = std::move(job);
  m.verifying = true;
  try {
    s.open();
  } catch (const std::exception& e) {
    m.pending_start.reset();
    m.verifying = false;
    return session::CommandResult::refused(e.what());
  }
  return session::CommandResult::ok();
}

void Machines::require_control(Machine& m, const std::string& client_id) {
  if (client_id.empty())
    throw ApiError{428, "client_id_required", "this command needs control of the machine: send X-Client-Id"};
  const double now = m.session->now();
  if (!m.control_holder.empty() && m.control_holder != client_id && now - m.control_seen > config_.limits.control_idle_s)
    set_control(m, "");  // the holder went quiet
  if (m.control_holder == client_id) {
    m.control_seen = now;
    return;
  }
  if (m.control_holder.empty())
    throw ApiError{409, "control_required",
                   "nobody holds control of machine '" + m.config.name + "': POST /api/v1/machines/" + m.config.name +
                       "/control first"};
  throw ApiError{409, "control_held", "client '" + m.control_holder + "' holds control of machine '" + m.config.name + "'"};
}

json Machines::control_json(const Machine& m, const std::string& client_id) const {
  return {{"holder", m.control_holder.empty() ? json(nullptr) : json(m.control_holder)},
          {"you", !client_id.empty() && client_id == m.control_holder}};
}

void Machines::set_control(Machine& m, const std::string& holder) {
  if (m.control_holder == holder) return;
  if (!m.control_holder.empty() && m.jog_ws_client) {
    m.session->jog_release();  // a jog never outlives its holder's control
    m.jog_ws_client = 0;
  }
  m.control_holder = holder;
  m.control_seen = m.session->now();
  spdlog::info("machine {}: control {}", m.config.name, holder.empty() ? std::string("released") : "held by " + holder);
  publish(m, {{"type", "control"}, {"holder", holder.empty() ? json(nullptr) : json(holder)}});
}

void Machines::touch(const std::string& client_id) {
  if (client_id.empty()) return;
  for (auto& m : machines_)
    if (m->control_holder == client_id) m->control_seen = m->session->now();
}

void Machines::client_gone(const std::string& client_id, std::uint64_t ws_client) {
  for (auto& m : machines_) {
    if (ws_client && m->jog_ws_client == ws_client) {
      m->session->jog_release();  // the dead man: a dropped socket stops its jog at once
      m->jog_ws_client = 0;
    }
    if (!client_id.empty() && m->control_holder == client_id && hub_.count(client_id) == 0) set_control(*m, "");
  }
}

namespace detail_machines {

const char* prompt_step(protocol::PromptKind k) {
  switch (k) {
    case protocol::PromptKind::MountTool: return "mount_tool";
    case protocol::PromptKind::ZeroManually: return "zero_manually";
    case protocol::PromptKind::Question: return "question";
    case protocol::PromptKind::Confirm: return "confirm";
  }
  return "question";
}

}  // namespace detail_machines

json Machines::tool_change(const Machine& m) const {
  const auto& s = *m.session;
  const auto& req = s.tool_change_request();
  if (!req) return nullptr;
  const auto snap = s.snapshot();
  const auto& prompt = snap.tool_prompt;
  const auto& cfg = s.tool_change_config();
  return {{"line", req->line},
          {"from_tool", req->from_tool},
          {"tool", req->to_tool},
          // The incoming tool as the library knows it: the operator checks the name and the stick-out.
          {"library_tool", req->to_tool > 0 && library_tool ? library_tool(m.config.name, req->to_tool) : json(nullptr)},
          {"description", req->note},
          {"method", cfg ? protocol::to_string(cfg->method) : "pause"},
          // "routine": the machine moves or probes by itself (wait); otherwise the operator's turn.
          {"step", prompt ? detail_machines::prompt_step(prompt->kind) : "routine"},
          {"prompt", prompt ? json{{"kind", detail_machines::prompt_step(prompt->kind)}, {"text", prompt->text}}
                            : json(nullptr)},
          // Jogs, probe_z and console lines are accepted now (and refused while the routine moves).
          {"operator_turn", prompt.has_value()}};
}

json Machines::routine(const Machine& m) const {
  const auto* r = m.session->routine();
  if (!r) return nullptr;
  const auto& p = r->pending_prompt();
  return {{"name", r->name()},
          {"prompt", p ? json{{"kind", detail_machines::prompt_step(p->kind)}, {"tool", p->tool}, {"text", p->text}}
                       : json(nullptr)}};
}

json Machines::tool_reference(const Machine& m) const {
  const auto& ref = m.session->tool_reference();
  if (!ref) return nullptr;
  return {{"tool", ref->tool},
          {"trigger_z", ref->trigger_z},
          {"offset_z", ref->offset_z},
          {"method", protocol::to_string(ref->method)},
          {"measured_tool", ref->measured_tool},
          {"measured_trigger_z", ref->measured_trigger_z ? json(*ref->measured_trigger_z) : json(nullptr)}};
}

json Machines::summary(const Machine& m) const {
  const auto& s = *m.session;
  const auto snap = s.snapshot();
  const auto st = s.status();
  return {{"name", m.config.name},
          {"port", m.config.port},
          {"link", to_string(s.link())},
          {"profile", snap.profile},
          {"state", st ? json(st->state_text) : json(nullptr)},
          {"alarm", s.in_alarm()},
          {"job_active", s.job_active()},
          {"jogging", snap.jogging},
          {"jog_held", s.engine() && s.engine()->jog().held()},
          {"control_holder", m.control_holder.empty() ? json(nullptr) : json(m.control_holder)},
          {"current_job", current_job ? current_job(m.config.name) : json(nullptr)}};
}

json Machines::state(const Machine& m) const {
  json j = summary(m);
  const auto snap = m.session->snapshot();
  j["banner"] = snap.banner;
  const auto& st = snap.status;
  if (st) {
    j["status"] = {{"state", protocol::to_string(st->state)}, {"state_text", st->state_text}, {"mpos", axes3(st->mpos)},
                   {"wpos", axes3(st->wpos)}, {"wco", axes3(st->wco)}, {"feed", opt(st->feed)},
                   {"spindle", opt(st->spindle)}, {"overrides", opt(snap.overrides)}, {"line", opt(st->line_number)},
                   {"pins", st->pins.value_or("")}};
  } else {
    j["status"] = nullptr;
  }
  j["buffer"] = {{"planner_free", st ? opt(st->planner_free) : json(nullptr)},
                 {"rx_free", st ? opt(st->rx_free) : json(nullptr)},
                 {"in_flight", snap.buffer.in_flight},
                 {"capacity", snap.buffer.capacity}};
  j["progress"] = {{"state", protocol::to_string(snap.progress.state)}, {"lines_sent", snap.progress.lines_sent},
                   {"lines_answered", snap.progress.lines_answered},
                   {"last_answered_line", snap.progress.last_answered_line},
                   {"total_lines", snap.progress.total_lines}};
  j["alarm_info"] = snap.alarm ? code_info_json(m.last_alarm) : json(nullptr);
  j["tool_change"] = tool_change(m);
  j["tool_in_spindle"] = snap.tool_in_spindle;
  j["routine"] = routine(m);
  j["tool_reference"] = tool_reference(m);
  j["tool_change_settings"] = tool_change_json(m.config.tool_change);
  return j;
}

json Machines::settings(const Machine& m) const {
  json s = json::object();
  for (const auto& [k, v] : m.session->settings()) s[cat({"$", std::to_string(k)})] = v;
  return {{"settings", s}};
}

}  // namespace cncstream::daemon
