#include "soak_run.hpp"

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>

#include "cncstream/jobs/resume_job.hpp"
#include "cncstream/session/job_journal.hpp"
#include "cncstream/session/machine_session.hpp"
#include "cncstream/transport/sha256.hpp"
#include "served_sim.hpp"
#include "soak_program.hpp"

namespace reliability {

namespace session = cncstream::session;
namespace protocol = cncstream::protocol;
using protocol::EventKind;
using protocol::JobOutcome;

std::size_t resident_kib() {
  std::ifstream f("/proc/self/statm");
  std::size_t pages = 0, resident = 0;
  f >> pages >> resident;
  return resident * static_cast<std::size_t>(::sysconf(_SC_PAGESIZE)) / 1024;
}

namespace {

// The faults that end a job, in the order a shuffled cycle deals them.
enum class Kind { Error, HardLimitLine, SoftLimit, AbortCycle, LimitSwitch, DropByte, CorruptByte, DropEol, CorruptEol, LostLink, None };
constexpr Kind kKinds[] = {Kind::Error,      Kind::HardLimitLine, Kind::SoftLimit,  Kind::AbortCycle, Kind::LimitSwitch,
                           Kind::DropByte,   Kind::CorruptByte,   Kind::DropEol,    Kind::CorruptEol, Kind::LostLink};

const char* name(Kind k) {
  switch (k) {
    case Kind::Error: return "error:N answer";
    case Kind::HardLimitLine: return "ALARM:1 with a line";
    case Kind::SoftLimit: return "ALARM:2 with a line";
    case Kind::AbortCycle: return "ALARM:3 with a line";
    case Kind::LimitSwitch: return "limit switch (ALARM:1 mid-move)";
    case Kind::DropByte: return "byte dropped";
    case Kind::CorruptByte: return "byte damaged";
    case Kind::DropEol: return "end of line dropped";
    case Kind::CorruptEol: return "end of line damaged";
    case Kind::LostLink: return "lost link";
    case Kind::None: return "none";
  }
  return "?";
}

bool wire_damage(Kind k) {
  return k == Kind::DropByte || k == Kind::CorruptByte || k == Kind::DropEol || k == Kind::CorruptEol;
}

class Soak {
 public:
  explicit Soak(const SoakOptions& o) : opt_(o), rng_(o.seed * 7919 + 1) {}

  SoakReport run() {
    const auto t0 = std::chrono::steady_clock::now();
    program_ = soak_program(opt_.lines, opt_.seed);
    times_.assign(program_.size() + 1, 0);
    std::filesystem::create_directories(opt_.dir);
    const auto file = opt_.dir / "soak.nc";
    {
      std::ofstream f(file);
      for (const auto& l : program_) f << l << "\n";
    }
    const auto db = opt_.dir / "soak.sqlite";
    std::filesystem::remove(db);
    sha_ = cncstream::transport::sha256_file(file);
    file_ = file;

    cncsim::MachineOptions mo;
    mo.strict = true;  // the streamer must never overflow the RX buffer
    mo.instant_waits = true;
    sim_ = std::make_unique<ServedSim>(mo, [this](cncsim::Machine& m) {
      m.set_line_observer([this](const cncsim::ExecutedLine& l) { on_executed(l); });
    });
    session::MachineOptions so;
    so.name = "soak";
    so.port = std::shared_ptr<session::MachinePort>(sim_.get(), [](session::MachinePort*) {});
    so.profiles_dir = CNCSTREAM_SOURCE_DIR "/firmware-profiles";
    session_ = std::make_unique<session::MachineSession>(io_, so);
    journal_ = std::make_unique<session::JobJournal>(*session_, db, "soak-sim", 0.1);
    auto sub = session_->subscribe([this](const session::SessionEvent& e) { on_event(e); });
    rss_every_ = std::max<std::size_t>(opt_.lines / 200, 50);
    sample_rss();

    session_->open();
    wait([&] { return session_->ready(); }, "the controller to be identified");

    std::vector<Kind> deck;
    std::size_t dealt = 0;
    session::JobInput job;
    job.file = file_;
    job.file_sha256 = sha_;
    job.lines = program_;
    job.total_lines = static_cast<std::int64_t>(program_.size());
    for (;;) {
      if (deck.empty()) {
        deck.assign(std::begin(kKinds), std::end(kKinds));
        std::shuffle(deck.begin(), deck.end(), rng_);
      }
      const Kind kind = dealt < opt_.faults ? deck.back() : Kind::None;
      if (kind != Kind::None) {
        deck.pop_back();
        ++dealt;
      }
      const long from = job.from_line;
      prepare(kind);
      const std::size_t errors_before = totals_.errors;
      run_job(std::move(job), kind);
      Segment& s = report_.segments.back();
      s.from_line = from;
      if (s.outcome == "completed") break;
      recover();
      note_applied(sim_->machine());
      if (wire_damage(kind) && totals_.errors > errors_before) s.fault += " (the line had no such byte; an error ended the job)";
      check_segment();
      if (report_.problems.size() > 20) break;
      job = resume_job();
      if (report_.segments.size() > opt_.faults * 3 + 10) {
        report_.problems.push_back("the run did not converge: more jobs than faults can explain");
        break;
      }
    }
    sim_->pause();
    check_segment();
    finish_accounting();
    session_->close();
    sample_rss();
    report_.power_cycles = static_cast<std::size_t>(sim_->power_cycles());
    report_.program_lines = program_.size();
    report_.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    report_.journal_rows = static_cast<std::size_t>(journal_rows());
    sub.reset();
    journal_.reset();
    session_.reset();
    sim_.reset();
    return report_;
  }

 private:
  // ---- waiting on the event loop -------------------------------------------

  template <typename Pred>
  void wait(Pred done, const std::string& what) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(opt_.wait_limit_s);
    while (!done()) {
      if (std::chrono::steady_clock::now() > end)
        throw std::runtime_error("soak: gave up waiting for " + what + ": " + diagnose());
      io_.run_one_for(std::chrono::milliseconds(50));
    }
  }

  // What the streamer and the simulator are doing, for a wait that timed out.
  std::string diagnose() {
    std::ostringstream o;
    o << "job " << report_.segments.size();
    if (!report_.segments.empty()) o << " (" << report_.segments.back().fault << ")";
    o << "; link " << session::to_string(session_->link());
    if (const auto* e = session_->engine()) {
      const auto& p = e->progress();
      o << "; job " << protocol::to_string(p.state) << ", " << p.lines_sent << " sent, " << p.lines_answered
        << " answered, last " << p.last_answered_line << "; " << e->buffer().in_flight << " bytes in flight";
      if (const auto st = e->status()) o << "; last status " << st->state_text;
    }
    sim_->pause();
    const cncsim::Machine& m = sim_->machine();
    o << "; simulator " << m.state_name() << ", " << m.lines_received() << " received, " << m.lines_answered()
      << " answered, " << m.lines_executed() << " run, RX " << m.rx_used() << " bytes, planner " << m.planner_blocks()
      << (m.vanished() ? ", vanished" : "") << (m.stalled() ? ", stalled" : "");
    o << "; recent warnings:";
    for (std::size_t i = report_.warnings.size() > 5 ? report_.warnings.size() - 5 : 0; i < report_.warnings.size(); ++i)
      o << " [" << report_.warnings[i] << "]";
    o << "; events:";
    for (const auto& t : recent_) o << " [" << t << "]";
    return o.str();
  }

  bool settled() const {
    const auto* e = session_->engine();
    return session_->ready() && e && !session_->job_active() && !e->busy();
  }

  // ---- the simulator's account -----------------------------------------------

  void on_executed(const cncsim::ExecutedLine& l) {  // on the simulator's thread
    if (l.n <= 0 || static_cast<std::size_t>(l.n) >= times_.size()) return;
    ++times_[static_cast<std::size_t>(l.n)];
    seg_max_n_ = std::max(seg_max_n_, l.n);
    max_n_ = std::max(max_n_, l.n);
  }

  // ---- one job ---------------------------------------------------------------

  void prepare(Kind kind) {
    sim_->pause();
    cncsim::Machine& m = sim_->machine();
    note_applied(m);
    cncsim::Faults& f = m.faults();
    f.error_at.clear();
    f.alarm_at.clear();
    f.stall_at.clear();
    f.drop_byte_at.clear();
    f.corrupt_byte_at.clear();
    f.vanish_after = 0;
    const std::size_t gap_hi = std::max<std::size_t>(200, 2 * opt_.lines / (opt_.faults + 1));
    std::uniform_int_distribution<std::size_t> gap(100, gap_hi);
    const std::size_t g = gap(rng_);
    const std::size_t at = m.lines_received() + g;
    // In-line damage hits a coordinate letter: X -> Y (or Y -> X) repeats a
    // word, a dropped X or Y leaves a number where a letter must be, so the
    // firmware always sees it. A damaged digit would run unseen (GRBL has no
    // checksum) and the machine would no longer follow the program the
    // resume planner reads: no host can account for that line.
    const char letter = rng_() % 2 ? 'X' : 'Y';
    plan_ = Plan{};
    switch (kind) {
      case Kind::Error: {
        const int codes[] = {1, 2, 20, 22, 33};
        f.error_at[at] = codes[g % 5];
        break;
      }
      case Kind::HardLimitLine: f.alarm_at[at] = 1; break;
      case Kind::SoftLimit: f.alarm_at[at] = 2; break;
      case Kind::AbortCycle: f.alarm_at[at] = 3; break;
      case Kind::LimitSwitch: plan_.limit_switch_after = g; break;
      case Kind::DropByte: f.drop_byte_at[at] = cncsim::ByteOfLine::first(letter); break;
      case Kind::CorruptByte: f.corrupt_byte_at[at] = cncsim::ByteOfLine::first(letter); break;
      case Kind::DropEol: f.drop_byte_at[at] = cncsim::ByteOfLine::end_of_line(); break;
      case Kind::CorruptEol: f.corrupt_byte_at[at] = cncsim::ByteOfLine::end_of_line(); break;
      case Kind::LostLink: f.vanish_after = m.lines_answered() + g; break;
      case Kind::None: break;
    }
    // A line without that letter (G0Z2, M8) is left alone: an error later
    // in the same job ends it all the same.
    if (wire_damage(kind)) f.error_at[at + 300] = 1;
    // Around the fault: a stall, override changes and a hold/resume cycle.
    std::uniform_int_distribution<std::size_t> before(1, g > 2 ? g - 1 : 1);
    if (rng_() % 2) f.stall_at[m.lines_received() + before(rng_)] = 0.2;
    for (int i = 0; i < 3; ++i) plan_.overrides.push_back(before(rng_));
    std::sort(plan_.overrides.begin(), plan_.overrides.end());
    plan_.hold_after = before(rng_);
    seg_max_n_ = 0;
    sim_->serve();
  }

  void run_job(session::JobInput job, Kind kind) {
    report_.segments.push_back(Segment{});
    report_.segments.back().fault = name(kind);
    job_answered_ = 0;
    holding_ = false;
    ended_.reset();
    job_id_before_ = journal_->job_id();
    if (auto r = session_->start_job(std::move(job)); !r) throw std::runtime_error("soak: job refused: " + r.reason);
    wait([&] { return ended_.has_value(); }, "the job to end");
  }

  // The operator brings the machine back to where a job can start.
  void recover() {
    const Segment& s = report_.segments.back();
    if (s.outcome == "disconnected") {
      wait([&] { return sim_->vanished(); }, "the simulator's port to close");
      sim_->pause();
      note_applied(sim_->machine());  // its last counts, before it goes
      sim_->power_cycle();
      session_->open();
      wait([&] { return session_->ready(); }, "the power-cycled controller to be identified");
    }
    wait([&] { return settled(); }, "the controller to settle after '" + s.outcome + "'");
    if (session_->in_alarm() || s.outcome == "alarm") {
      unlocked_ = false;
      if (auto r = session_->unlock(); !r) throw std::runtime_error("soak: unlock refused: " + r.reason);
      wait([&] { return unlocked_ && settled() && !session_->in_alarm(); }, "the controller to unlock");
    }
    sim_->pause();  // a quiet machine: its account can be read
  }

  // ---- what the operator does while the job runs -------------------------------

  void on_event(const session::SessionEvent& e) {
    if (e.kind == session::SessionEventKind::JobEnded) {
      Segment& s = report_.segments.back();
      s.outcome = protocol::to_string(e.outcome);
      s.last_line = e.last_answered_line;
      if (e.outcome != JobOutcome::Completed && e.outcome != JobOutcome::Error) s.report += e.text;
      ended_ = e.outcome;
      return;
    }
    if (e.kind != session::SessionEventKind::Controller) {
      remember(std::string("session: ") + e.text);
      return;
    }
    const protocol::Event& ev = e.controller;
    if (ev.kind != EventKind::LineAnswered && ev.kind != EventKind::Status)
      remember(std::string(protocol::to_string(ev.kind)) + ": " + ev.text);
    switch (ev.kind) {
      case EventKind::LineAnswered: on_answered(); break;
      case EventKind::LineError:
        report_.segments.back().report += ev.text + "\n";
        session_->stop();  // no operator decides to skip a line: stop, then resume from the journal
        break;
      case EventKind::Alarm: report_.segments.back().report += ev.text + "\n"; break;
      case EventKind::Status:
        if (holding_ && ev.status && ev.status->state == protocol::MachineState::Hold && ev.status->substate == 0) {
          holding_ = false;
          if (session_->resume()) ++report_.holds;
        }
        break;
      case EventKind::CommandAnswered:
        if (ev.line_text == "$X") unlocked_ = true;
        break;
      case EventKind::Warning:
        report_.warnings.push_back(ev.text);
        if (ev.source_line > 0) {  // a line the controller will never answer: as after an error
          report_.segments.back().report += ev.text + "\n";
          session_->stop();
        }
        break;
      default: break;
    }
  }

  void on_answered() {
    ++job_answered_;
    ++report_.answered;
    if (report_.answered % rss_every_ == 0) sample_rss();
    if (!session_->job_active() || session_->engine()->progress().state != protocol::JobState::Running) return;
    static constexpr protocol::Realtime kOverrides[] = {
        protocol::Realtime::FeedOvPlus10,    protocol::Realtime::FeedOvMinus10,  protocol::Realtime::FeedOvReset,
        protocol::Realtime::RapidOvLow,      protocol::Realtime::RapidOvMedium,  protocol::Realtime::RapidOvReset,
        protocol::Realtime::SpindleOvPlus10, protocol::Realtime::SpindleOvMinus10, protocol::Realtime::SpindleOvReset};
    while (!plan_.overrides.empty() && job_answered_ >= plan_.overrides.front()) {
      plan_.overrides.erase(plan_.overrides.begin());
      if (session_->realtime(kOverrides[rng_() % std::size(kOverrides)])) ++report_.overrides;
    }
    if (plan_.hold_after && job_answered_ >= plan_.hold_after) {
      plan_.hold_after = 0;
      if (session_->hold()) holding_ = true;
    }
    if (plan_.limit_switch_after && job_answered_ >= plan_.limit_switch_after) {
      plan_.limit_switch_after = 0;
      sim_->pause();
      sim_->machine().inject_hard_limit();
      ++limit_switches_;
      sim_->serve();
    }
  }

  // ---- checks ----------------------------------------------------------------------

  void problem(const std::string& what) {
    std::ostringstream o;
    o << "job " << report_.segments.size() << " (" << report_.segments.back().fault << ", "
      << report_.segments.back().outcome << "): " << what;
    report_.problems.push_back(o.str());
  }

  // The journal against the session's end of job and the simulator's account.
  void check_segment() {
    Segment& s = report_.segments.back();
    auto& j = journal_->journal();
    const std::int64_t id = journal_->job_id();
    if (id == job_id_before_) return problem("the job has no journal row");
    const auto row = j.job(id);
    const auto last = j.last_progress(id);
    if (!row || !last) return problem("the journal lost the job or its rows");
    if (row->outcome.value_or("interrupted") != s.outcome)
      problem("journaled outcome '" + row->outcome.value_or("interrupted") + "' but the job ended '" + s.outcome + "'");
    if (last->reason != "end") problem("the last row is '" + last->reason + "', not the end row");
    if (last->last_line != s.last_line)
      problem("journal says line " + std::to_string(last->last_line) + " was answered last, the session " +
              std::to_string(s.last_line));
    if (row->planner_blocks != 15) problem("the journal gives a planner of " + std::to_string(row->planner_blocks) + " blocks, not GRBL's 15");
    if (row->resumed_from != (report_.segments.size() > 1 ? job_id_before_ : 0))
      problem("resumed_from is " + std::to_string(row->resumed_from));
    // The simulator never runs a line the streamer has not seen answered.
    // (Except after a lost end of line: the controller answers two lines
    // with one error, and until the reset that follows the streamer's count
    // runs one line behind; it cannot know. That errs on the safe side.)
    const bool merged = s.fault.find("end of line") != std::string::npos;
    if (seg_max_n_ > s.last_line + (merged ? 1 : 0))
      problem("the simulator ran N" + std::to_string(seg_max_n_) + " but line " + std::to_string(s.last_line) +
              " is the last answered");
    // Answered and not run: at most the planner's 15 blocks and the line that failed.
    for (long n = std::max<long>(s.from_line + 1, 1); n <= s.last_line; ++n)
      if (times_[static_cast<std::size_t>(n)] == 0) ++s.unexecuted_answered;
    // (An end of line lost between two lines makes them one: one error, two lines.)
    if (s.outcome != "completed" && s.unexecuted_answered > 18)
      problem(std::to_string(s.unexecuted_answered) + " answered lines did not run: more than the planner holds");
    if (s.outcome != "completed" && s.report.empty()) problem("the fault ended the job without a report");
  }

  session::JobInput resume_job() {
    auto& j = journal_->journal();
    const std::int64_t id = journal_->job_id();
    const auto last = j.last_progress(id);
    cncstream::jobs::ResumeInput in;
    in.file = file_;
    in.file_sha256 = sha_;
    in.lines = std::move(program_);  // lent to the planner, taken back below
    if (last) {
      in.last_line = last->last_line;
      if (last->status_work_pos)
        in.status_work_pos = cncstream::geometry::Vec3{(*last->status_work_pos)[0], (*last->status_work_pos)[1],
                                             (*last->status_work_pos)[2]};
      in.status_line = last->status_line;
    }
    if (const auto row = j.job(id)) {
      if (row->resumed_from > 0) in.resumed_after = row->from_line;
      in.planner_blocks = static_cast<int>(row->planner_blocks);
    }
    in.error_lines = j.progress_lines(id, "error");
    in.dwell_s = 0.05;
    auto plan = cncstream::jobs::plan_resume(in);
    program_ = std::move(in.lines);
    report_.segments.back().resume = plan.reason;
    if (!in.error_lines.empty()) {
      report_.segments.back().resume += " [error rows:";
      for (auto e : in.error_lines) report_.segments.back().resume += " " + std::to_string(e);
      report_.segments.back().resume += "]";
    }
    // Nothing may be skipped: the resume starts at or before the first line never run.
    const auto first_missing = static_cast<long>(
        std::find(times_.begin() + 1, times_.end(), std::uint16_t{0}) - times_.begin());
    if (plan.from_line >= first_missing)
      problem("resume continues after line " + std::to_string(plan.from_line) + " (" + plan.reason + ") but line " +
              std::to_string(first_missing) + " never ran");
    windows_.push_back({plan.from_line, max_n_});
    if (max_n_ > plan.from_line) report_.replay_window_lines += static_cast<std::size_t>(max_n_ - plan.from_line);
    session::JobInput job;
    job.file = plan.file;
    job.file_sha256 = plan.file_sha256;
    job.total_lines = plan.total_lines;
    job.resumed_from = id;
    job.from_line = plan.from_line;
    job.lines = std::move(plan.lines);
    job.source_lines = std::move(plan.source_lines);
    job_id_before_ = id;
    return job;
  }

  void finish_accounting() {
    for (std::size_t n = 1; n < times_.size(); ++n) {
      if (times_[n] == 0) {
        if (++report_.missing <= 5) report_.problems.push_back("line N" + std::to_string(n) + " never ran");
        continue;
      }
      ++report_.ran;
      report_.ran_again += times_[n] - 1u;
      std::size_t allowed = 1;
      for (const auto& [from, upto] : windows_)
        if (static_cast<long>(n) > from && static_cast<long>(n) <= upto) ++allowed;
      if (times_[n] > allowed)
        report_.problems.push_back("line N" + std::to_string(n) + " ran " + std::to_string(times_[n]) +
                                   " times; resumes went back over it " + std::to_string(allowed - 1) + " times");
    }
    note_applied(sim_->machine());
    report_.faults["limit switch (ALARM:1 mid-move)"] = limit_switches_;
  }

  void note_applied(const cncsim::Machine& m) {
    // Counts of this machine so far, plus those of machines power-cycled away.
    const auto& a = m.faults_applied();
    if (sim_->power_cycles() != counted_machine_) {  // a new machine: its counts start at zero
      counted_machine_ = sim_->power_cycles();
      base_ = totals_;
    }
    totals_.dropped_bytes = base_.dropped_bytes + a.dropped_bytes;
    totals_.corrupted_bytes = base_.corrupted_bytes + a.corrupted_bytes;
    totals_.errors = base_.errors + a.errors;
    totals_.alarms = base_.alarms + a.alarms;
    totals_.stalls = base_.stalls + a.stalls;
    report_.faults["bytes dropped"] = totals_.dropped_bytes;
    report_.faults["bytes damaged"] = totals_.corrupted_bytes;
    report_.faults["error:N answers"] = totals_.errors;
    report_.faults["alarms with a line"] = totals_.alarms;
    report_.faults["stalls"] = totals_.stalls;
    report_.faults["lost links"] = static_cast<std::size_t>(sim_->power_cycles()) + (a.vanished ? 1 : 0);
  }

  std::int64_t journal_rows() {
    std::int64_t rows = 0;
    for (const auto& job : journal_->journal().jobs(100000)) rows += journal_->journal().progress_count(job.id);
    return rows;
  }

  void remember(std::string text) {
    recent_.push_back(std::move(text));
    if (recent_.size() > 12) recent_.erase(recent_.begin());
  }

  void sample_rss() { report_.rss.push_back({report_.answered, resident_kib()}); }

  struct Plan {
    std::vector<std::size_t> overrides;  // after this many answered lines of the job
    std::size_t hold_after = 0;
    std::size_t limit_switch_after = 0;
  };

  SoakOptions opt_;
  std::mt19937_64 rng_;
  std::vector<std::string> program_;
  std::filesystem::path file_;
  std::string sha_;
  std::vector<std::uint16_t> times_;  // times_[N]: how often the simulator ran line N
  long seg_max_n_ = 0, max_n_ = 0;
  std::vector<std::pair<long, long>> windows_;  // (from_line, highest line run before) of each resume
  boost::asio::io_context io_;
  boost::asio::executor_work_guard<boost::asio::io_context::executor_type> work_{io_.get_executor()};
  std::unique_ptr<ServedSim> sim_;
  std::unique_ptr<session::MachineSession> session_;
  std::unique_ptr<session::JobJournal> journal_;
  Plan plan_;
  std::size_t job_answered_ = 0;
  bool holding_ = false, unlocked_ = false;
  std::optional<JobOutcome> ended_;
  std::int64_t job_id_before_ = 0;
  std::size_t rss_every_ = 1000;
  std::size_t limit_switches_ = 0;
  int counted_machine_ = 0;  // power cycles when its counts were last taken
  cncsim::FaultsApplied base_, totals_;
  SoakReport report_;
  std::vector<std::string> recent_;
};

}  // namespace

SoakReport run_soak(const SoakOptions& options) { return Soak(options).run(); }

}  // namespace reliability
