// `cncstream jobs`: what the journal knows about past jobs, newest first, with
// the last answered line and modal state needed for a restart.
#include <iomanip>
#include <iostream>
#include <memory>

#include "cncstream/gcode/modal_words.hpp"
#include "cncstream/transport/journal.hpp"
#include "commands.hpp"

namespace cncstream::app {

void register_jobs(CLI::App& app, CommandRegistry& registry) {
  struct Opts {
    std::string journal;
    int limit = 20;
    long long show = 0;
  };
  auto o = std::make_shared<Opts>();
  auto* sub = app.add_subcommand("jobs", "List journaled jobs (outcome, last answered line, modal state)");
  sub->add_option("--journal", o->journal, "Journal database (default: $XDG_STATE_HOME/cncstream/journal.sqlite)");
  sub->add_option("-n,--limit", o->limit, "How many jobs to list")->check(CLI::Range(1, 100000));
  sub->add_option("--show", o->show, "Show one job in detail, with a restart preamble");
  registry.add(sub, [o] {
    const auto path = o->journal.empty() ? transport::Journal::default_path() : std::filesystem::path(o->journal);
    if (!std::filesystem::exists(path)) {
      std::cout << "no journal at " << path.string() << " (no job has been streamed yet)\n";
      return 0;
    }
    transport::Journal j(path);
    if (o->show) {
      const auto job = j.job(o->show);
      if (!job) {
        std::cerr << "cncstream: error: no job " << o->show << " in " << path.string() << "\n";
        return 1;
      }
      std::cout << "job " << job->id << ": " << job->file << "\n  sha256 " << job->file_sha256 << "\n  "
                << job->profile << " on " << job->port << ", " << job->mode << ", " << job->total_lines
                << " lines\n  started " << job->started_at << ", ended " << job->ended_at.value_or("never")
                << "\n  outcome: " << job->outcome.value_or("interrupted (the process died mid-job)") << "\n";
      if (!job->message.empty()) std::cout << "  " << job->message << "\n";
      if (job->resumed_from)
        std::cout << "  resumes job " << job->resumed_from << " after file line " << job->from_line << "\n";
      if (const auto p = j.last_progress(job->id)) {
        std::cout << "  last record (" << p->reason << ", " << p->at << "): " << p->lines_ok
                  << " lines answered ok, last answered file line " << p->last_line << "\n  modal state: "
                  << gcode::modal_json(p->modal) << "\n  to continue (after homing and checking the work offset): "
                  << "cncstream resume " << job->id
                  << " PORT, which plans the retract, travel, spindle and plunge from the program itself\n";
      }
      return 0;
    }
    // The daemon's (cncstreamd) queue: jobs created but not run yet, or running now.
    int queued = 0;
    for (const auto& d : j.daemon_jobs(o->limit)) {
      if (d.ended_at) continue;
      if (queued++ == 0) std::cout << "cncstreamd queue:\n";
      std::cout << std::setw(5) << d.id << "  " << d.created_at << "  " << std::setw(12) << std::left << d.state
                << std::right << "  " << d.machine << "  " << d.file_name;
      if (d.journal_id) std::cout << "  (journal job " << d.journal_id << ")";
      std::cout << "\n";
    }
    if (queued) std::cout << "journaled runs (the CLI's and cncstreamd's):\n";
    const auto jobs = j.jobs(o->limit);
    if (jobs.empty()) std::cout << "no jobs in " << path.string() << "\n";
    for (const auto& job : jobs) {
      const auto p = j.last_progress(job.id);
      std::cout << std::setw(5) << job.id << "  " << job.started_at << "  " << std::setw(12) << std::left
                << job.outcome.value_or("interrupted") << std::right << "  "
                << (p ? std::to_string(p->last_line) : "0") << "/" << job.total_lines << "  " << job.profile << "  "
                << job.file << "\n";
    }
    return 0;
  });
}

}  // namespace cncstream::app
