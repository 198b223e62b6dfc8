#include "cncstream/session/machine_session.hpp"

#include <fmt/core.h>

#include <boost/asio/post.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "cncstream/gcode/tool_change_line.hpp"
#include "cncstream/protocol/grbl_session.hpp"
#include "cncstream/protocol/line_cleaner.hpp"
#include "cncstream/protocol/machine_actions.hpp"
#include "cncstream/protocol/marlin_session.hpp"
#include "cncstream/protocol/response.hpp"
#include "cncstream/protocol/travel_check.hpp"

namespace cncstream::session {

using namespace protocol;

namespace {

constexpr double kNever = std::numeric_limits<double>::infinity();

bool marlin_family(const FirmwareProfile& p) { return p.flow == FlowControl::SendResponse; }

std::string fixed3(double v) { return fmt::format("{:.3f}", v); }

}  // namespace

const char* to_string(LinkState s) {
  switch (s) {
    case LinkState::Closed: return "closed";
    case LinkState::Connecting: return "connecting";
    case LinkState::Ready: return "ready";
    case LinkState::Disconnected: return "disconnected";
  }
  return "?";
}

void Subscription::reset() {
  if (auto l = list_.lock())
    for (auto& e : l->entries)
      if (e.first == id_) e.second = nullptr;  // removed from the vector at the next emit
  list_.reset();
  id_ = 0;
}

MachineSession::MachineSession(boost::asio::io_context& io, MachineOptions options)
    : io_(io),
      opt_(std::move(options)),
      t0_(std::chrono::steady_clock::now()),
      timer_(io),
      reconnect_timer_(io),
      subscribers_(std::make_shared<SubscriberList>()),
      alive_(std::make_shared<bool>(true)) {
  if (!opt_.port) throw std::invalid_argument("machine '" + opt_.name + "': no port given");
  profiles_ = load_firmware_profiles(opt_.profiles_dir);
  if (opt_.force_profile &&
      std::none_of(profiles_.begin(), profiles_.end(), [&](const auto& p) { return p.id == *opt_.force_profile; }))
    throw std::invalid_argument("no firmware profile named '" + *opt_.force_profile + "'");
}

MachineSession::~MachineSession() {
  *alive_ = false;
  // A destructor that throws ends the program (std::terminate). Cancelling a
  // timer may throw system_error, posting may throw bad_alloc: the session is
  // gone either way, and the handlers check *alive_.
  try {
    timer_.cancel();
    reconnect_timer_.cancel();
    if (transport_) transport_->close();
    // Handlers still queued for this transport hold it alive (see retire below).
    if (transport_) boost::asio::post(io_, [t = std::move(transport_)] {});
  } catch (...) {
    // nothing is left to tell or undo
  }
}

double MachineSession::now() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
}

std::size_t MachineSession::bytes_written() const {
  return bytes_written_before_ + (transport_ ? transport_->bytes_written() : 0);
}

Subscription MachineSession::subscribe(std::function<void(const SessionEvent&)> fn) {
  const auto id = subscribers_->next_id++;
  subscribers_->entries.emplace_back(id, std::move(fn));
  return Subscription(subscribers_, id);
}

void MachineSession::emit(SessionEvent e) {
  e.at = now();
  e.link = link_;
  auto list = subscribers_;  // a subscriber may drop its handle, or the session, meanwhile
  auto& v = list->entries;
  // Removed entries go only at the outermost emit: a subscriber's command may emit again.
  if (list->depth == 0) std::erase_if(v, [](const auto& p) { return !p.second; });
  ++list->depth;
  for (std::size_t i = 0; i < v.size(); ++i)  // index: subscribing from a callback appends
    if (v[i].second) {
      auto fn = v[i].second;  // a copy: the callback may unsubscribe itself
      try {
        fn(e);
      } catch (...) {
        --list->depth;
        throw;
      }
    }
  --list->depth;
}

void MachineSession::log(const std::string& text) {
  SessionEvent e;
  e.kind = SessionEventKind::Log;
  e.text = text;
  emit(std::move(e));
}

void MachineSession::set_link(LinkState s, const std::string& why) {
  link_ = s;
  SessionEvent e;
  e.kind = SessionEventKind::Link;
  e.text = why;
  emit(std::move(e));
}

// ---- connection ----------------------------------------------------------

void MachineSession::open() {
  if (link_ == LinkState::Connecting || link_ == LinkState::Ready) return;
  reconnect_timer_.cancel();
  try {
    connect_transport();
  } catch (const std::exception& e) {
    if (link_ == LinkState::Disconnected) schedule_reconnect();
    throw;
  }
}

void MachineSession::connect_transport() {
  const std::string path = opt_.port->path();
  auto t = std::make_shared<transport::SerialTransport>(io_, opt_.serial);
  t->open(path);  // throws naming the path
  if (transport_) {
    bytes_written_before_ += transport_->bytes_written();
    boost::asio::post(io_, [old = std::move(transport_)] {});
  }
  transport_ = std::move(t);
  engine_.reset();
  identifier_ = std::make_unique<FirmwareIdentifier>(profiles_, opt_.identify);
  id_splitter_ = LineSplitter{};
  pending_after_id_.clear();
  settings_phase_ = SettingsPhase::NotStarted;
  settings_.clear();
  report_inches_ = false;  // until this controller's $13 is read
  alarm_ = false;
  probe_pending_ = false;
  banner_.clear();
  set_link(LinkState::Connecting, "identifying the controller on " + opt_.port->describe());
  log("opened " + path + " at " + std::to_string(opt_.serial.baud) + " baud");
  if (!transport_->lock_note().empty()) log(transport_->lock_note());
  std::weak_ptr<bool> alive = alive_;
  transport::SerialTransport* self = transport_.get();
  transport_->start(
      [this, alive, self](std::string_view bytes) {
        if (!alive.lock() || transport_.get() != self) return;
        on_data(bytes);
      },
      [this, alive, self](const std::string& reason) {
        if (!alive.lock() || transport_.get() != self) return;
        on_port_closed(reason);
      });
  opt_.port->opened();
  identifier_->start(now());
  transport_->write(identifier_->take_output());
  arm_timer();
}

CommandResult MachineSession::close() {
  if (job_active()) return CommandResult::refused("a job is running: stop it before closing the port");
  reconnect_timer_.cancel();
  if (engine_ && engine_->jogging()) {
    engine_->jog_release();
    drain();
  }
  if (transport_) transport_->close_when_flushed();
  engine_.reset();
  identifier_.reset();
  timer_.cancel();
  timer_armed_ = false;
  set_link(LinkState::Closed, "closed");
  return CommandResult::ok();
}

void MachineSession::on_port_closed(const std::string& reason) {
  log("port closed: " + reason);
  end_machine_routine("the controller disconnected (" + reason + ")");
  if (engine_) {
    engine_->disconnected();  // a running job ends as Disconnected; a jog is forgotten
    drain();
    if (link_ == LinkState::Closed) return;  // a subscriber closed the session on the job's end
  }
  engine_.reset();
  identifier_.reset();
  alarm_ = false;
  probe_pending_ = false;
  timer_.cancel();
  timer_armed_ = false;
  set_link(LinkState::Disconnected, "controller disconnected (" + reason + ")");
  schedule_reconnect();
}

void MachineSession::schedule_reconnect() {
  if (!(opt_.reconnect_interval_s > 0)) return;
  reconnect_timer_.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(opt_.reconnect_interval_s)));
  std::weak_ptr<bool> alive = alive_;
  reconnect_timer_.async_wait([this, alive](const boost::system::error_code& ec) {
    if (ec || !alive.lock() || link_ != LinkState::Disconnected) return;
    try {
      connect_transport();
    } catch (const std::exception&) {
      schedule_reconnect();  // not back yet
    }
  });
}

// ---- bytes in ------------------------------------------------------------

void MachineSession::on_data(std::string_view bytes) {
  if (engine_) {
    engine_->on_bytes(bytes, now());
    drain();
    arm_timer();
    return;
  }
  if (!identifier_) return;
  id_splitter_.feed(bytes, [&](std::string_view line) {
    if (!identifier_->done()) identifier_->on_line(line, now());
    else if (settings_phase_ == SettingsPhase::Reading) on_settings_line(line);
    else pending_after_id_.append(line).push_back('\n');
  });
  for (const auto& n : identifier_->take_notes()) log("warning: " + n);
  transport_->write(identifier_->take_output());
  after_identification();
  arm_timer();
}

void MachineSession::after_identification() {
  if (engine_ || !identifier_ || !identifier_->done()) return;
  if (settings_phase_ == SettingsPhase::NotStarted) {
    const auto& id = identifier_->result();
    for (const auto& w : id.warnings) log("warning: " + w);
    profile_ = id.profile;
    banner_ = id.banner;
    if (opt_.force_profile)
      for (const auto& p : profiles_)
        if (p.id == *opt_.force_profile) profile_ = p;
    if (opt_.read_settings && !marlin_family(profile_)) {
      settings_phase_ = SettingsPhase::Reading;
      settings_deadline_ = now() + opt_.settings_timeout_s;
      transport_->write("$$\n");
    } else {
      settings_phase_ = SettingsPhase::Done;
    }
  }
  if (settings_phase_ == SettingsPhase::Reading && now() >= settings_deadline_) {
    settings_done(fmt::format("no answer within {:g} s", opt_.settings_timeout_s));
  }
  if (settings_phase_ == SettingsPhase::Done) start_engine();
}

void MachineSession::on_settings_line(std::string_view line) {
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.remove_suffix(1);
  // `$$` prints its settings before its ok: an ok before any is not its answer.
  if (line == "ok" && settings_.empty()) return;
  if (line == "ok") settings_done("");
  else if (line.rfind("error:", 0) == 0) settings_done("the controller answered " + std::string(line));
  else if (const auto kv = parse_setting_line(line)) settings_[kv->first] = kv->second;
}

void MachineSession::settings_done(const std::string& why) {
  settings_phase_ = SettingsPhase::Done;
  if (!why.empty()) {
    log("warning: controller settings ($$) not read: " + why);
    return;
  }
  if (const auto it = settings_.find(13); it != settings_.end()) report_inches_ = it->second == 1;
  if (engine_) engine_->set_jog_limits(protocol::jog_limits_from(settings_));
  SessionEvent e;
  e.kind = SessionEventKind::Settings;
  e.text = std::to_string(settings_.size()) + " settings read";
  emit(std::move(e));
}

void MachineSession::start_engine() {
  log("controller: " + profile_.id + (banner_.empty() ? "" : " ('" + banner_ + "')") + ", RX " +
      std::to_string(profile_.rx_buffer_size) + " bytes, lines up to " + std::to_string(profile_.line_length_limit));
  if (marlin_family(profile_)) engine_ = std::make_unique<MarlinSession>(profile_);
  else engine_ = std::make_unique<GrblSession>(profile_, opt_.grbl);
  if (settings_phase_ == SettingsPhase::Done) engine_->set_jog_limits(protocol::jog_limits_from(settings_));
  set_link(LinkState::Ready, "controller " + profile_.id + " ready");
  if (!pending_after_id_.empty()) engine_->on_bytes(std::exchange(pending_after_id_, {}), now());
  engine_->tick(now());
  drain();
}

// ---- engine output and events --------------------------------------------

void MachineSession::drain() {
  if (!engine_) return;
  if (transport_) transport_->write(engine_->take_output());
  for (auto& ev : engine_->take_events()) {
    if (ev.kind == EventKind::Alarm) {
      alarm_ = true;
      probe_pending_ = false;  // a probe that misses alarms (ALARM:4/5)
      forget_tool_reference("an alarm");
    }
    if (ev.kind == EventKind::Reset) forget_tool_reference("a reset");
    if (probe_pending_ && ev.kind == EventKind::Info)
      if (auto p = protocol::parse_probe_report(ev.text)) on_probe_report(*p);
    if (ev.kind == EventKind::Status && ev.status) {
      alarm_ = ev.status->state == MachineState::Alarm;
      in_mm(*ev.status);
    }
    if (routine_) tool_change_event(ev);
    if (machine_routine_) machine_routine_event(ev);
    SessionEvent e;
    e.kind = SessionEventKind::Controller;
    e.text = ev.text;
    e.controller = ev;
    emit(e);
    if (ev.kind == EventKind::JobFinished && job_) {
      SessionEvent end;
      end.kind = SessionEventKind::JobEnded;
      const auto& p = engine_->progress();
      end.outcome = p.outcome;
      end.text = ev.text;
      end.last_answered_line = p.last_answered_line;
      end.lines_answered = p.lines_answered;
      end.job = &*job_;
      emit(end);
      job_.reset();
    }
    if (!engine_) return;  // a subscriber closed the session
  }
  if (!routine_ && job_ && engine_->tool_change_stop()) start_tool_change();
  if (routine_) pump_tool_change();
  if (machine_routine_) pump_machine_routine();
  if (transport_ && engine_) transport_->write(engine_->take_output());
}

// ---- tool changes -------------------------------------------------------------

void MachineSession::forget_tool_reference(const char* why) {
  if (!tool_reference_) return;
  tool_reference_.reset();
  log(std::string("tool-length reference forgotten after ") + why + ": the next change measures it again");
}

void MachineSession::start_tool_change() {
  const auto stop = engine_->tool_change_stop();
  protocol::ToolChangeRequest req;
  req.line = stop->source_line;
  req.from_tool = tool_in_spindle_;
  req.to_tool = stop->tool;
  req.modal = engine_->modal();
  for (const auto& c : gcode::find_tool_changes(job_->lines)) {
    const long src = job_->source_lines.empty() ? static_cast<long>(c.index) + 1 : job_->source_lines[c.index];
    if (src == stop->source_line) req.note = c.note;
  }
  routine_ = std::make_unique<protocol::ToolChangeRoutine>(*opt_.tool_change, req, tool_reference_);
  routine_request_ = req;
  routine_line_.clear();
  log(fmt::format("tool change at file line {}: T{} -> T{} ({})", req.line, req.from_tool, req.to_tool,
                  protocol::to_string(opt_.tool_change->method)));
  if (report_inches_) {
    routine_->abort("the controller reports in inches ($13=1): set $13=0 for tool changes");
    return;
  }
  routine_->start();
}

void MachineSession::tool_change_event(const protocol::Event& ev) {
  feed_routine(*routine_, routine_line_, ev);
  // An alarm, a reset, a lost link or a stop ended the job mid-routine.
  if (ev.kind == EventKind::JobFinished) end_tool_change(ev.text);
}

void MachineSession::pump_tool_change() {
  if (!routine_) return;
  if (auto p = routine_->take_prompt()) {
    SessionEvent e;
    e.kind = SessionEventKind::ToolChange;
    e.text = p->text;
    e.tool_prompt = *p;
    emit(e);
    if (!routine_ || !engine_) return;
  }
  send_routine_realtime(*routine_);
  send_routine_line(*routine_, routine_line_);
  if (routine_->finished()) end_tool_change("");
}

void MachineSession::end_tool_change(const std::string& why) {
  if (!routine_) return;
  if (!routine_->finished()) routine_->abort(why.empty() ? std::string("the job ended") : why);
  const auto rec = routine_->record();
  const bool ok = routine_->succeeded();
  const std::string failure = routine_->failure();
  tool_in_spindle_ = rec.tool;
  if (ok) tool_reference_ = routine_->reference();
  else tool_reference_.reset();
  routine_.reset();
  routine_request_.reset();
  routine_line_.clear();
  SessionEvent e;
  e.kind = SessionEventKind::ToolChange;
  e.text = ok ? rec.note : failure + (rec.length_known ? "" : "; the length of the tool in the spindle is unknown");
  e.tool_record = rec;
  emit(e);
  if (!engine_) return;
  if (ok) engine_->tool_change_done();
  else if (job_active()) engine_->abort_job(failure);
}

bool MachineSession::operator_turn() const {
  return routine_ && routine_->pending_prompt() && engine_ &&
         engine_->progress().state == protocol::JobState::ToolChange;
}

CommandResult MachineSession::set_tool_change(std::optional<protocol::ToolChangeConfig> config) {
  if (job_active()) return CommandResult::refused("tool-change settings: a job is running");
  opt_.tool_change = config;
  return CommandResult::ok();
}

CommandResult MachineSession::tool_change_confirm() {
  if (!operator_turn()) return CommandResult::refused("confirm: no tool change is waiting for the operator");
  // The routine's next move (safe Z, the probe) must not meet a jog still running.
  if (engine_->jogging()) return CommandResult::refused("confirm: a jog is running; wait until the machine is still");
  routine_->confirm();
  drain();
  arm_timer();
  return CommandResult::ok();
}

CommandResult MachineSession::tool_change_decline() {
  if (!operator_turn()) return CommandResult::refused("decline: no tool change is waiting for the operator");
  routine_->decline();
  drain();
  arm_timer();
  return CommandResult::ok();
}

void MachineSession::arm_timer() {
  double at = kNever;
  if (engine_) at = engine_->next_deadline();
  else if (identifier_ && !identifier_->done()) at = identifier_->next_deadline();
  else if (settings_phase_ == SettingsPhase::Reading) at = settings_deadline_;
  if (!std::isfinite(at)) return;
  if (timer_armed_ && timer_at_ <= at) return;  // fires early enough; on_timer re-arms
  timer_armed_ = true;
  timer_at_ = at;
  timer_.expires_at(t0_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                              std::chrono::duration<double>(at)));
  std::weak_ptr<bool> alive = alive_;
  timer_.async_wait([this, alive](const boost::system::error_code& ec) {
    if (ec == boost::asio::error::operation_aborted || !alive.lock()) return;
    timer_armed_ = false;
    on_timer();
  });
}

void MachineSession::on_timer() {
  const double t = now();
  if (engine_) {
    engine_->tick(t);
    drain();
  } else if (identifier_) {
    if (!identifier_->done()) {
      identifier_->tick(t);
      for (const auto& n : identifier_->take_notes()) log("warning: " + n);
      if (transport_) transport_->write(identifier_->take_output());
    }
    after_identification();
  }
  arm_timer();
}

// ---- commands ------------------------------------------------------------

bool MachineSession::job_active() const { return engine_ && is_active(engine_->progress().state); }

CommandResult MachineSession::needs_engine(const char* what) const {
  if (engine_) return CommandResult::ok();
  switch (link_) {
    case LinkState::Connecting:
      return CommandResult::refused(std::string(what) + ": the controller is still being identified");
    case LinkState::Disconnected:
      return CommandResult::refused(std::string(what) + ": the controller is disconnected");
    default: return CommandResult::refused(std::string(what) + ": the port is not open");
  }
}

CommandResult MachineSession::refuse_in_alarm(const char* what) const {
  if (!alarm_) return CommandResult::ok();
  return CommandResult::refused(std::string(what) + ": the controller is in alarm; unlock ($X), home or reset first");
}

CommandResult MachineSession::start_job(JobInput job, JobMode mode) {
  if (auto r = needs_engine("start a job"); !r) return r;
  if (job_active()) return CommandResult::refused("start a job: a job is already running");
  if (auto r = refuse_during_routine("start a job"); !r) return r;
  if (engine_->jogging()) return CommandResult::refused("start a job: a jog is running; release it first");
  if (auto r = refuse_in_alarm("start a job"); !r) return r;
  if (mode != JobMode::Run && marlin_family(profile_))
    return CommandResult::refused("start a job: " + profile_.id + " has no check mode ($C)");
  if (!job.source_lines.empty() && job.source_lines.size() != job.lines.size())
    return CommandResult::refused("start a job: one source line per line expected");
  CleanOptions clean;
  if (marlin_family(profile_)) {
    clean.strip_whitespace = false;
    clean.reject_realtime_chars = false;
  }
  auto program = prepare_program(job.lines, job.file.string(), profile_.line_length_limit, clean);
  if (!program.errors.empty()) {
    std::string all = job.file.string() + " cannot be sent to " + profile_.id + ":";
    for (const auto& e : program.errors) all += "\n  " + e;
    return CommandResult::refused(all);
  }
  // Larger than the machine can move: refused before its first line (check
  // mode moves nothing and reports the program's own errors).
  if (mode != JobMode::Check)
    if (const auto travel = protocol::max_travel_from(settings_)) {
      const gcode::ProgramExtent extent = job.extent ? *job.extent : gcode::program_extent(job.lines);
      if (const auto why = protocol::travel_refusal(extent, *travel))
        return CommandResult::refused(std::string("start a job: ").append(job.file.string()).append(": ").append(*why));
    }
  if (!job.source_lines.empty())
    for (std::size_t i = 0; i < program.lines.size(); ++i) program.lines[i].source_line = job.source_lines[i];
  // Tool changes are ours to run (GRBL holds on M0 where nothing can be
  // jogged or probed, and refuses M6): the lines are marked, never sent.
  if (opt_.tool_change && !marlin_family(profile_)) {
    const auto changes = gcode::find_tool_changes(job.lines);
    if (!changes.empty() && mode != JobMode::Check)
      if (const auto why = controller_tool_change_refusal(*opt_.tool_change))
        return CommandResult::refused("start a job: " + job.file.string() + " changes tools: " + *why);
    for (const auto& c : changes) program.lines[c.index].tool_change = c.tool;
    if (const int first = gcode::first_tool(job.lines); first > 0 && job.resumed_from == 0) {
      if (tool_in_spindle_ != first) tool_reference_.reset();
      tool_in_spindle_ = first;
    }
  }
  try {
    engine_->start_job(std::move(program), mode, now());
  } catch (const std::exception& e) {
    return CommandResult::refused(std::string("start a job: ") + e.what());
  }
  job_ = std::move(job);
  SessionEvent e;
  e.kind = SessionEventKind::JobStarted;
  e.text = mode == JobMode::Check ? "check" : mode == JobMode::CheckThenRun ? "check+run" : "run";
  e.job = &*job_;
  emit(e);
  drain();
  arm_timer();
  return CommandResult::ok();
}

CommandResult MachineSession::hold() {
  if (auto r = needs_engine("hold"); !r) return r;
  if (engine_->jogging()) return jog_release();
  if (job_active()) engine_->pause();
  else if (!engine_->realtime(Realtime::FeedHold)) return CommandResult::refused("hold: no job is running");
  drain();
  return CommandResult::ok();
}

CommandResult MachineSession::resume() {
  if (auto r = needs_engine("resume"); !r) return r;
  if (auto r = refuse_in_alarm("resume"); !r) return r;
  if (job_active()) engine_->resume();
  else if (!engine_->realtime(Realtime::CycleStart)) return CommandResult::refused("resume: no job is running");
  drain();
  return CommandResult::ok();
}

CommandResult MachineSession::toggle_hold() {
  if (auto r = needs_engine("hold/resume"); !r) return r;
  if (!job_active()) return CommandResult::refused("hold/resume: no job is running");
  engine_->toggle_pause();
  drain();
  return CommandResult::ok();
}

CommandResult MachineSession::stop() {
  if (auto r = needs_engine("stop"); !r) return r;
  if (engine_->jogging()) engine_->jog_cancel();
  if (machine_routine_) {
    // Nothing more of it is sent; the hold stops the move in flight.
    end_machine_routine("stopped by the operator");
    engine_->realtime(Realtime::FeedHold);
  }
  if (job_active()) engine_->stop();
  drain();
  arm_timer();
  return CommandResult::ok();
}

CommandResult MachineSession::realtime(Realtime rt) {
  if (auto r = needs_engine("real-time command"); !r) return r;
  if (rt != Realtime::SoftReset && rt != Realtime::StatusReport && rt != Realtime::FeedHold && alarm_)
    return refuse_in_alarm("real-time command");
  if (!engine_->realtime(rt))
    return CommandResult::refused(std::string("real-time command '") + realtime_key(rt) + "' is not available on " +
                                  profile_.id);
  drain();
  return CommandResult::ok();
}

CommandResult MachineSession::refuse_jog() const {
  if (auto r = needs_engine("jog"); !r) return r;
  // At a tool change's prompt the machine is idle and the operator's.
  if (job_active() && !operator_turn()) return CommandResult::refused("jog: a job is running");
  if (!routine_operator_turn())
    if (auto r = refuse_during_routine("jog"); !r) return r;
  if (auto r = refuse_in_alarm("jog"); !r) return r;
  if (probe_pending_) return CommandResult::refused("jog: probing Z; wait for it to finish");
  return CommandResult::ok();
}

CommandResult MachineSession::jog_step(const JogDirection& dir, double distance_mm, double feed_mm_min) {
  if (auto r = refuse_jog(); !r) return r;
  std::string why = engine_->jog_step(dir, distance_mm, feed_mm_min, now());
  drain();
  arm_timer();
  return why.empty() ? CommandResult::ok() : CommandResult::refused(std::move(why));
}

CommandResult MachineSession::jog_start(const JogDirection& dir, double feed_mm_min, double lease_s) {
  if (auto r = refuse_jog(); !r) return r;
  std::string why = engine_->jog_start(dir, feed_mm_min, lease_s, now());
  drain();
  arm_timer();
  return why.empty() ? CommandResult::ok() : CommandResult::refused(std::move(why));
}

CommandResult MachineSession::jog_renew() {
  if (!engine_ || !engine_->jog_renew(now())) return CommandResult::refused("jog: no continuous jog is running");
  arm_timer();
  return CommandResult::ok();
}

CommandResult MachineSession::jog_release() {
  if (engine_) {
    engine_->jog_release();
    drain();
    arm_timer();
  }
  return CommandResult::ok();
}

double MachineSession::max_jog_feed() const {
  const auto l = engine_ ? engine_->jog().limits() : protocol::JogLimits{};
  return std::min({l.max_rate_mm_min[0], l.max_rate_mm_min[1], l.max_rate_mm_min[2]});
}

// ---- machine actions ---------------------------------------------------------

CommandResult MachineSession::action(const char* what, const std::function<std::vector<std::string>()>& lines) {
  if (auto r = needs_engine(what); !r) return r;
  if (job_active() && !operator_turn()) return CommandResult::refused(std::string(what) + ": a job is running");
  if (!routine_operator_turn())
    if (auto r = refuse_during_routine(what); !r) return r;
  if (engine_->jogging()) return CommandResult::refused(std::string(what) + ": a jog is running");
  if (auto r = refuse_in_alarm(what); !r) return r;
  if (probe_pending_) return CommandResult::refused(std::string(what) + ": probing Z; wait for it to finish");
  try {
    for (const auto& l : lines()) engine_->send_command(l);
  } catch (const std::exception& e) {
    return CommandResult::refused(e.what());
  }
  drain();
  return CommandResult::ok();
}

std::optional<double> MachineSession::work_z() const {
  const auto st = status();
  if (!st || !st->wpos) return std::nullopt;
  return (*st->wpos)[2];
}

CommandResult MachineSession::zero_axes(const std::string& axes) {
  const auto family = marlin_family(profile_) ? protocol::ActionFamily::Marlin : protocol::ActionFamily::Grbl;
  auto r = action("zero", [&] { return protocol::zero_axes_lines(axes, family); });
  if (r && axes.find_first_of("Zz") != std::string::npos) forget_tool_reference("a re-zero of Z");
  return r;
}

CommandResult MachineSession::safe_z() {
  return action("safe Z", [&] { return protocol::safe_z_lines(opt_.actions, work_z()); });
}

CommandResult MachineSession::go_to_work_zero() {
  return action("go to work zero", [&] { return protocol::go_to_work_zero_lines(opt_.actions, work_z()); });
}

CommandResult MachineSession::spindle(bool on) {
  if (!on && engine_ && !job_active()) {
    // Stopping the spindle is never refused for a jog or an alarm.
    engine_->send_command("M5");
    drain();
    return CommandResult::ok();
  }
  // Never a spinning bit while the operator mounts, zeroes or the routine probes.
  if (on && (operator_turn() || routine_operator_turn()))
    return CommandResult::refused("spindle on: a tool change is waiting for the operator");
  return action(on ? "spindle on" : "spindle off", [&] { return protocol::spindle_lines(on, opt_.actions); });
}

CommandResult MachineSession::probe_z() {
  if (engine_ && marlin_family(profile_))
    return CommandResult::refused("probe Z: not supported on " + profile_.id + " (no G38.2 in its profile)");
  if (in_controller_tool_state())
    return CommandResult::refused(
        "probe Z: grblHAL refuses G38.x in its Tool state (error:40); jog down to the work and zero Z");
  auto r = action("probe Z", [&] { return protocol::probe_z_lines(opt_.actions); });
  if (r) {
    probe_pending_ = true;
    log("probing Z: searching down up to " + fixed3(opt_.actions.probe_travel_mm) + " mm for the touch plate");
  }
  return r;
}

// The probe's answer: set work Z at the touch point, or say it missed.
void MachineSession::on_probe_report(const protocol::ProbeReport& p) {
  probe_pending_ = false;
  if (!p.touched) {
    log("probe Z: no touch within " + fixed3(opt_.actions.probe_travel_mm) + " mm; work Z unchanged");
    return;
  }
  const double touch = p.z * (report_inches_ ? 25.4 : 1.0);
  for (const auto& l : protocol::probe_finish_lines(opt_.actions, touch)) engine_->send_command(l);
  log("probe Z: touched at machine Z " + fixed3(touch) + "; work Z set to the plate's " +
      fixed3(opt_.actions.probe_plate_mm) + " mm there");
}

CommandResult MachineSession::console(const std::string& line) {
  if (auto r = needs_engine("console"); !r) return r;
  if (job_active() && !operator_turn())
    return CommandResult::refused("console: a job is running; lines are refused until it ends");
  if (!routine_operator_turn())
    if (auto r = refuse_during_routine("console"); !r) return r;
  if (engine_->jogging()) return CommandResult::refused("console: a jog is running");
  if (alarm_ && line != "$X" && line != "$H")
    return refuse_in_alarm("console");
  try {
    const std::string upper = [&] {
      std::string u;
      for (char c : line) u.push_back(static_cast<char>(std::toupper(static_cast<unsigned char>(c))));
      return u;
    }();
    // A homing moves the machine's frame under a tool change's measurements: not at its prompt.
    if (upper.rfind("$H", 0) == 0 && (routine_ || machine_routine_))
      return CommandResult::refused("console: no homing during a tool change or routine; decline it first");
    if (upper.find("G10") != std::string::npos || upper.find("G92") != std::string::npos ||
        upper.rfind("$H", 0) == 0)
      forget_tool_reference("a change of the work offset or a homing");
    engine_->send_command(line);
  } catch (const std::exception& e) {
    return CommandResult::refused(e.what());
  }
  drain();
  return CommandResult::ok();
}

// Marlin has no alarm lock: M999 clears its "stopped" state; G28 homes.
CommandResult MachineSession::unlock() {
  if (auto r = needs_engine("unlock"); !r) return r;
  if (job_active()) return CommandResult::refused("unlock: a job is running");
  engine_->send_command(marlin_family(profile_) ? "M999" : "$X");
  drain();
  return CommandResult::ok();
}

// Homing is also a way out of an alarm (GRBL's ALARM:11 asks for it).
CommandResult MachineSession::home() {
  if (auto r = needs_engine("home"); !r) return r;
  if (job_active()) return CommandResult::refused("home: a job is running");
  if (auto r = refuse_during_routine("home"); !r) return r;
  if (engine_->jogging()) return CommandResult::refused("home: a jog is running");
  engine_->send_command(marlin_family(profile_) ? "G28" : "$H");
  forget_tool_reference("a homing");
  drain();
  return CommandResult::ok();
}

CommandResult MachineSession::reset() {
  if (auto r = needs_engine("reset"); !r) return r;
  if (job_active()) return stop();  // a reset in motion loses the position: stop does it safely
  if (!engine_->realtime(Realtime::SoftReset))
    return CommandResult::refused("reset: " + profile_.id + " has no soft reset");
  drain();
  return CommandResult::ok();
}

// Positions are millimetres inside; a controller with $13=1 reports inches.
void MachineSession::in_mm(StatusReport& r) const {
  if (!report_inches_) return;
  for (auto* axes : {&r.mpos, &r.wpos, &r.wco})
    if (*axes)
      for (auto& v : **axes) v *= 25.4;
}

std::optional<StatusReport> MachineSession::status() const {
  auto r = engine_ ? engine_->status() : std::nullopt;
  if (r) in_mm(*r);
  return r;
}

MachineSnapshot MachineSession::snapshot() const {
  MachineSnapshot s;
  s.name = opt_.name;
  s.link = link_;
  s.now = now();
  s.alarm = alarm_;
  if (engine_) {
    s.profile = engine_->profile().id;
    s.banner = banner_;
    s.progress = engine_->progress();
    s.progress.check_errors.clear();
    s.status = status();
    s.overrides = engine_->overrides();
    s.buffer = engine_->buffer();
    s.jogging = engine_->jogging();
    s.job_active = job_active();
    if (routine_) s.tool_prompt = routine_->pending_prompt();
    s.tool_in_spindle = tool_in_spindle_;
  }
  return s;
}

}  // namespace cncstream::session
