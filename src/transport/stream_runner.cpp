#include "cncstream/transport/stream_runner.hpp"

#include <boost/asio/steady_timer.hpp>

#include <chrono>
#include <stdexcept>

#include "cncstream/protocol/grbl_session.hpp"
#include "cncstream/protocol/marlin_session.hpp"
#include "cncstream/protocol/response.hpp"
#include "cncstream/transport/journal.hpp"
#include "cncstream/transport/sha256.hpp"

namespace cncstream::transport {

using namespace protocol;

StreamRunner::StreamRunner(RunnerOptions opt) : opt_(std::move(opt)) {}
StreamRunner::~StreamRunner() = default;

namespace {

std::string reason_for(const Event& e) {
  switch (e.kind) {
    case EventKind::LineError: return "error";
    case EventKind::CheckError: return "check-error";
    case EventKind::Alarm: return "alarm";
    case EventKind::JobState: return "state";
    case EventKind::JobFinished: return "end";
    case EventKind::Reset: return "reset";
    default: return "periodic";
  }
}

}  // namespace

JobInput job_from_file(const std::filesystem::path& gcode_path) {
  JobInput j;
  j.file = gcode_path;
  j.lines = read_gcode_lines(gcode_path.string());
  j.file_sha256 = sha256_file(gcode_path);
  j.total_lines = static_cast<std::int64_t>(j.lines.size());
  return j;
}

RunResult StreamRunner::run(const std::filesystem::path& gcode_path) { return run(job_from_file(gcode_path)); }

RunResult StreamRunner::run(const JobInput& job) {
  auto log = [&](const std::string& s) {
    if (opt_.on_log) opt_.on_log(s);
  };
  const auto& file_lines = job.lines;
  const auto& gcode_path = job.file;
  if (!job.source_lines.empty() && job.source_lines.size() != job.lines.size())
    throw std::invalid_argument("job input: one source line per line expected");
  auto profiles = load_firmware_profiles(opt_.profiles_dir);

  boost::asio::io_context io;
  SerialTransport port(io, opt_.serial);
  port.open(opt_.port);
  log("opened " + opt_.port + " at " + std::to_string(opt_.serial.baud) + " baud");
  if (opt_.on_port_opened) opt_.on_port_opened();

  const auto t0 = std::chrono::steady_clock::now();
  auto now = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };

  FirmwareIdentifier identifier(profiles, opt_.identify);
  identifier.start(now());
  LineSplitter id_splitter;
  std::unique_ptr<ProtocolEngine> engine;
  std::unique_ptr<Journal> journal;
  std::int64_t job_id = 0;
  RunResult result;
  bool done = false;
  bool dirty = false;
  double last_row = -1;
  std::string pending_after_id;  // bytes that arrived after the identification answer
  // The last status report's work position (mm), state, and the last answered
  // line when it came: where the machine really was, for resume.
  std::optional<std::array<double, 3>> status_work_pos;
  std::int64_t status_line = 0;
  std::string machine_state;
  bool report_inches = false;  // $13=1

  bool journal_closed = false;  // the end row is written: the job's record is final
  auto record = [&](const std::string& reason) {
    if (!journal || !engine || journal_closed) return;
    ProgressRecord p;
    p.job_id = job_id;
    // A check pass moves nothing: its lines are not progress a resume could skip.
    const bool checking = engine->progress().mode == JobMode::Check;
    p.lines_ok = checking ? 0 : static_cast<std::int64_t>(engine->progress().lines_answered);
    p.last_line = checking ? 0 : engine->progress().last_answered_line;
    p.reason = reason;
    if (auto* g = dynamic_cast<GrblSession*>(engine.get())) p.modal = g->modal();
    else if (auto* m = dynamic_cast<MarlinSession*>(engine.get())) p.modal = m->modal();
    p.status_work_pos = status_work_pos;
    p.status_line = status_line;
    p.machine_state = machine_state;
    journal->record_progress(p);
    last_row = now();
    dirty = false;
  };

  std::function<void()> timer_cancel = [] {};
  auto finish = [&](JobOutcome o, const std::string& msg) {
    if (done) return;
    done = true;
    result.outcome = o;
    result.message = msg;
    if (engine) {
      result.lines_answered = engine->progress().lines_answered;
      result.last_answered_line = engine->progress().last_answered_line;
    }
    if (journal && job_id) {
      record("end");
      journal->end_job(job_id, to_string(o), msg);
      journal_closed = true;
    }
    timer_cancel();
    port.close_when_flushed();  // the loop ends when the last byte is out
  };

  auto drain = [&] {
    if (!engine) return;
    port.write(engine->take_output());
    for (auto& e : engine->take_events()) {
      if (e.kind == EventKind::LineAnswered) {
        dirty = true;  // journaled at most every progress_interval_s (below)
      } else if (e.kind == EventKind::Status) {
        if (e.status) machine_state = e.status->state_text;
        status_line = engine->progress().last_answered_line;
        if (const auto& w = e.status ? e.status->wpos : std::nullopt) {
          const double k = report_inches ? 25.4 : 1.0;
          const std::array<double, 3> p{(*w)[0] * k, (*w)[1] * k, (*w)[2] * k};
          // A long move answers no lines: the moving position alone is worth a row.
          if (status_work_pos != p && job_id) dirty = true;
          status_work_pos = p;
        }
      } else if (e.kind != EventKind::Info && e.kind != EventKind::Warning && e.kind != EventKind::CommandAnswered) {
        record(reason_for(e));
      }
      if (opt_.on_event) opt_.on_event(e);
      if (e.kind == EventKind::JobFinished) finish(engine->progress().outcome, e.text);
    }
    if (!done && dirty && now() - last_row >= opt_.progress_interval_s) record("periodic");
  };

  // After identification: choose the profile, then (GRBL family) read `$$`.
  enum class SettingsPhase { NotStarted, Reading, Done } settings_phase = SettingsPhase::NotStarted;
  double settings_deadline = 0;
  GrblSettings settings;
  FirmwareProfile profile;
  auto choose_profile = [&] {
    const auto& id = identifier.result();
    for (const auto& w : id.warnings) log("warning: " + w);
    profile = id.profile;
    if (opt_.force_profile) {
      bool found = false;
      for (const auto& p : profiles)
        if (p.id == *opt_.force_profile) {
          profile = p;
          found = true;
        }
      if (!found) throw std::invalid_argument("no firmware profile named '" + *opt_.force_profile + "'");
    }
  };
  auto settings_done = [&](const std::string& why) {
    settings_phase = SettingsPhase::Done;
    if (!why.empty()) log("warning: controller settings ($$) not read: " + why);
    else if (opt_.on_settings) opt_.on_settings(settings);
    if (const auto it = settings.find(13); it != settings.end()) report_inches = it->second == 1;
  };
  auto on_settings_line = [&](std::string_view line) {
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.remove_suffix(1);
    if (line == "ok") settings_done("");
    else if (line.rfind("error:", 0) == 0) settings_done("the controller answered " + std::string(line));
    else if (const auto kv = parse_setting_line(line)) settings[kv->first] = kv->second;
  };

  auto start_engine = [&] {
    const auto& id = identifier.result();
    result.profile = profile.id;
    log("controller: " + profile.id + (id.banner.empty() ? "" : " ('" + id.banner + "')") + ", RX " +
        std::to_string(profile.rx_buffer_size) + " bytes, lines up to " + std::to_string(profile.line_length_limit));
    CleanOptions clean;
    if (profile.flow == FlowControl::SendResponse) {
      clean.strip_whitespace = false;
      clean.reject_realtime_chars = false;
    }
    auto program = prepare_program(file_lines, gcode_path.string(), profile.line_length_limit, clean);
    if (!program.errors.empty()) {
      std::string all = gcode_path.string() + " cannot be sent to " + profile.id + ":";
      for (const auto& e : program.errors) all += "\n  " + e;
      throw std::invalid_argument(all);
    }
    if (!job.source_lines.empty())
      for (std::size_t i = 0; i < program.lines.size(); ++i) program.lines[i].source_line = job.source_lines[i];
    if (profile.flow == FlowControl::SendResponse) engine = std::make_unique<MarlinSession>(profile);
    else engine = std::make_unique<GrblSession>(profile);
    if (opt_.journal_path) {
      journal = std::make_unique<Journal>(*opt_.journal_path);
      job_id = journal->begin_job(std::filesystem::absolute(gcode_path).string(), job.file_sha256, profile.id,
                                  opt_.port, opt_.mode == JobMode::Check ? "check" : opt_.mode == JobMode::CheckThenRun ? "check+run" : "run", job.total_lines,
                                  job.resumed_from, job.from_line);
      result.job_id = job_id;
    }
    engine->start_job(std::move(program), opt_.mode, now());
    if (!pending_after_id.empty()) engine->on_bytes(std::exchange(pending_after_id, {}), now());
    drain();
  };

  // Moves on from identification: settings read, then the engine.
  auto after_identification = [&] {
    if (engine || !identifier.done()) return;
    if (settings_phase == SettingsPhase::NotStarted) {
      choose_profile();
      if (opt_.read_settings && profile.flow != FlowControl::SendResponse) {
        settings_phase = SettingsPhase::Reading;
        settings_deadline = now() + opt_.settings_timeout_s;
        port.write("$$\n");
      } else {
        settings_phase = SettingsPhase::Done;
      }
    }
    if (settings_phase == SettingsPhase::Reading && now() > settings_deadline)
      settings_done("no answer within " + std::to_string(opt_.settings_timeout_s) + " s");
    if (settings_phase == SettingsPhase::Done) start_engine();
  };

  std::exception_ptr failure;
  auto guarded = [&](auto&& f) {
    try {
      f();
    } catch (...) {
      if (!failure) failure = std::current_exception();
      port.close();
      io.stop();
    }
  };

  port.start(
      [&](std::string_view bytes) {
        guarded([&] {
          if (engine) {
            engine->on_bytes(bytes, now());
            drain();
            return;
          }
          id_splitter.feed(bytes, [&](std::string_view line) {
            if (!identifier.done()) identifier.on_line(line, now());
            else if (settings_phase == SettingsPhase::Reading) on_settings_line(line);
            else if (engine) engine->on_bytes(std::string(line) + "\n", now());
            else pending_after_id.append(line).push_back('\n');
          });
          port.write(identifier.take_output());
          after_identification();
          if (engine) drain();
        });
      },
      [&](const std::string& reason) {
        guarded([&] {
          log("port closed: " + reason);
          if (engine) {
            engine->disconnected();
            drain();
          }
          finish(JobOutcome::Disconnected,
                 "controller disconnected (" + reason + "); last answered file line " +
                     std::to_string(engine ? engine->progress().last_answered_line : 0));
        });
      });

  auto report_snapshot = [&](double t) {
    if (!opt_.on_tick || !engine) return;
    RunnerSnapshot snap;
    snap.now = t;
    snap.profile = engine->profile().id;
    snap.progress = engine->progress();
    snap.progress.check_errors.clear();
    if (auto* g = dynamic_cast<GrblSession*>(engine.get())) {
      snap.status = g->status().last();
      snap.overrides = g->status().overrides();
      snap.rx_in_flight = g->counter().in_flight_bytes();
      snap.rx_size = engine->profile().rx_buffer_size;
    }
    opt_.on_tick(snap);
  };

  boost::asio::steady_timer timer(io);
  timer_cancel = [&] { timer.cancel(); };
  std::function<void()> schedule = [&] {
    timer.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(opt_.tick_s)));
    timer.async_wait([&](const boost::system::error_code& ec) {
      if (ec || done) return;
      guarded([&] {
        const double t = now();
        if (!engine) {
          if (!identifier.done()) identifier.tick(t);
          port.write(identifier.take_output());
          after_identification();
        } else {
          if (stop_requested_.exchange(false)) {
            log("stop requested: holding, then resetting once motion has stopped");
            engine->stop();
          }
          std::deque<Request> reqs;
          {
            std::lock_guard<std::mutex> l(mu_);
            reqs.swap(requests_);
          }
          for (const auto& q : reqs) {
            if (q.kind == Request::Pause) engine->pause();
            else if (q.kind == Request::Resume) engine->resume();
            else if (q.kind == Request::TogglePause) engine->toggle_pause();
            else if (auto* g = dynamic_cast<GrblSession*>(engine.get()); !g || !g->realtime(q.realtime)) {
              Event w{EventKind::Warning, std::string("real-time command '") + realtime_key(q.realtime) +
                                              "' is not available on " + engine->profile().id};
              if (opt_.on_event) opt_.on_event(w);
            }
          }
          engine->tick(t);
          drain();
          report_snapshot(t);
        }
        if (opt_.max_run_s > 0 && t > opt_.max_run_s && !done) {
          if (engine) engine->disconnected();
          finish(JobOutcome::Error, "gave up after " + std::to_string(opt_.max_run_s) + " s");
        }
      });
      if (!done) schedule();
    });
  };
  schedule();
  io.run();
  if (!failure) report_snapshot(now());  // the final state, not the last tick's
  result.bytes_written = port.bytes_written();
  result.seconds = now();
  if (failure) {
    if (journal && job_id && !done) journal->end_job(job_id, "error", "runner failure");
    std::rethrow_exception(failure);
  }
  return result;
}

}  // namespace cncstream::transport
