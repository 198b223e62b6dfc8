#pragma once
// The journal as a subscriber of a machine session: a job row when a job
// starts, progress rows (at most every `interval_s` while lines are answered,
// at once for errors, alarms, job-state changes and resets), and the end row.
// Each row holds the modal state after the last answered line and the last
// status report's work position, so resume finds the line being cut.
#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "cncstream/session/machine_session.hpp"
#include "cncstream/transport/journal.hpp"

namespace cncstream::session {

class JobJournal {
 public:
  JobJournal(MachineSession& session, const std::filesystem::path& db, std::string port_label,
             double interval_s = 0.1);
  // The journal id of the current or last job (0: none yet).
  std::int64_t job_id() const { return job_id_; }
  transport::Journal& journal() { return journal_; }
  // Ends the current job's record now, with its end row, when the job did
  // not end by itself (its runner gave up or failed with it still running).
  void end_now(const std::string& outcome, const std::string& message);

 private:
  void on_event(const SessionEvent& e);
  // `line`: the row's last_line when it is about one line (the one that
  // failed); else the last answered line now.
  void record(const std::string& reason, long line = 0);

  MachineSession& session_;
  transport::Journal journal_;
  std::string port_label_;
  double interval_s_;
  std::int64_t job_id_ = 0;
  bool open_ = false;  // a job row without its end row
  bool dirty_ = false;
  double last_row_ = -1e9;
  std::optional<std::array<double, 3>> status_work_pos_;
  std::int64_t status_line_ = 0;
  std::string machine_state_;
  Subscription sub_;
};

}  // namespace cncstream::session
