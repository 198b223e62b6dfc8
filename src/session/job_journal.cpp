#include "cncstream/session/job_journal.hpp"

namespace cncstream::session {

using protocol::EventKind;

namespace {

std::string reason_for(EventKind k) {
  switch (k) {
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

JobJournal::JobJournal(MachineSession& session, const std::filesystem::path& db, std::string port_label,
                       double interval_s)
    : session_(session), journal_(db), port_label_(std::move(port_label)), interval_s_(interval_s) {
  sub_ = session_.subscribe([this](const SessionEvent& e) { on_event(e); });
}

void JobJournal::record(const std::string& reason, long line) {
  const auto* engine = session_.engine();
  if (!open_ || !engine) return;
  transport::ProgressRecord p;
  p.job_id = job_id_;
  // A check pass moves nothing: its lines are not progress a resume could skip.
  const bool checking = engine->progress().mode == protocol::JobMode::Check;
  p.lines_ok = checking ? 0 : static_cast<std::int64_t>(engine->progress().lines_answered);
  p.last_line = checking ? 0 : line > 0 ? line : engine->progress().last_answered_line;
  p.reason = reason;
  p.modal = engine->modal();
  if (const auto st = session_.status(); st && st->wco)
    p.wco = std::array<double, 3>{(*st->wco)[0], (*st->wco)[1], (*st->wco)[2]};
  p.status_work_pos = status_work_pos_;
  p.status_line = status_line_;
  p.machine_state = machine_state_;
  journal_.record_progress(p);
  last_row_ = session_.now();
  dirty_ = false;
}

void JobJournal::end_now(const std::string& outcome, const std::string& message) {
  if (!open_) return;
  record("end");
  journal_.end_job(job_id_, outcome, message);
  open_ = false;
}

void JobJournal::on_event(const SessionEvent& e) {
  switch (e.kind) {
    case SessionEventKind::JobStarted: {
      const auto* engine = session_.engine();
      job_id_ = journal_.begin_job(std::filesystem::absolute(e.job->file).string(), e.job->file_sha256,
                                   engine ? engine->profile().id : "", port_label_, e.text, e.job->total_lines,
                                   e.job->resumed_from, e.job->from_line, engine ? engine->profile().planner_blocks : 0);
      open_ = true;
      dirty_ = false;
      status_work_pos_.reset();
      status_line_ = 0;
      machine_state_.clear();
      return;
    }
    case SessionEventKind::JobEnded:
      if (!open_) return;
      record("end");
      journal_.end_job(job_id_, protocol::to_string(e.outcome), e.text);
      open_ = false;
      return;
    case SessionEventKind::ToolChange:
      if (open_ && e.tool_record) {
        const auto& r = *e.tool_record;
        transport::ToolChangeRow row;
        row.job_id = job_id_;
        row.line = r.line;
        row.tool = r.tool;
        row.method = r.skipped ? "skipped" : protocol::to_string(r.method);
        row.offset_z = r.offset_z;
        row.length_known = r.length_known;
        row.note = r.note;
        journal_.record_tool_change(row);
      }
      return;
    case SessionEventKind::Routine:
      // Outside a job (routines never run in one): what it did, and the tool it left.
      if (e.routine_succeeded) {
        transport::RoutineRow row;
        row.port = port_label_;
        row.name = e.routine_name;
        row.succeeded = *e.routine_succeeded;
        row.text = e.text;
        if (const auto& r = e.tool_record) {
          row.tool_routine = true;
          row.tool = r->tool;
          row.method = r->skipped ? "skipped" : protocol::to_string(r->method);
          row.offset_z = r->offset_z;
          row.length_known = r->length_known;
        }
        journal_.record_routine(row);
      }
      return;
    case SessionEventKind::Controller: break;
    default: return;
  }
  if (!open_) return;
  const auto& ev = e.controller;
  if (ev.kind == EventKind::LineAnswered) {
    dirty_ = true;  // journaled at most every interval_s (below)
  } else if (ev.kind == EventKind::Status) {
    if (ev.status) machine_state_ = ev.status->state_text;
    if (const auto* engine = session_.engine()) status_line_ = engine->progress().last_answered_line;
    if (const auto& w = ev.status ? ev.status->wpos : std::nullopt) {
      const std::array<double, 3> p{(*w)[0], (*w)[1], (*w)[2]};
      // A long move answers no lines: the moving position alone is worth a row.
      if (status_work_pos_ != p) dirty_ = true;
      status_work_pos_ = p;
    }
  } else if (ev.kind == EventKind::JobFinished) {
    return;  // the end row comes with JobEnded
  } else if (ev.kind == EventKind::LineError) {
    // The line that failed: by the time the event is delivered the engine
    // may have taken more answers from the same read.
    record(reason_for(ev.kind), ev.source_line);
  } else if (ev.kind != EventKind::Info && ev.kind != EventKind::Warning && ev.kind != EventKind::CommandAnswered) {
    record(reason_for(ev.kind));
  }
  if (dirty_ && e.at - last_row_ >= interval_s_) record("periodic");
}

}  // namespace cncstream::session
