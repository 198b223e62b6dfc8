#pragma once
// The job journal: an SQLite database (WAL, synchronous=FULL) that records each
// job and its progress so that, after a crash, a disconnect or a kill, the
// operator knows exactly which lines the controller answered and the modal
// state at that line. Every write is its own committed transaction.
#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "cncstream/gcode/interpreter.hpp"

struct sqlite3;

namespace cncstream::transport {

class JournalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct JobRecord {
  std::int64_t id = 0;
  std::string file;
  std::string file_sha256;
  std::string profile;
  std::string port;
  std::string mode;  // "run" | "check"
  std::int64_t total_lines = 0;
  std::string started_at;  // ISO 8601 UTC
  std::optional<std::string> ended_at;
  std::optional<std::string> outcome;  // nullopt: never ended (killed, crashed)
  std::string message;
  std::int64_t resumed_from = 0;  // the job this one resumes (0: a fresh job)
  std::int64_t from_line = 0;     // the file line the resumed job continued after
  // The controller's planner depth when the job ran (0: not journaled, an
  // older journal): how many answered lines it may not have run yet.
  std::int64_t planner_blocks = 0;
};

struct ProgressRecord {
  std::int64_t job_id = 0;
  std::string at;
  std::int64_t lines_ok = 0;   // file lines answered ok (blank lines count once passed)
  std::int64_t last_line = 0;  // 1-based file line of the last answer; an "error" row: the line that failed
  std::string reason;          // "periodic", "error", "alarm", "stop", "end", ...
  gcode::ParserState modal;  // modal groups, feed, spindle speed and tool (the rest is not kept)
  std::optional<std::array<double, 3>> wco;  // work offset the controller reported (MPos - WPos), mm
  // The controller's last status report before this row: its work position
  // (mm) and state, and the last answered file line when it came. The machine
  // was then on a line at most one planner queue before that one, so resume
  // can find the line it was cutting instead of trusting the last `ok`.
  std::optional<std::array<double, 3>> status_work_pos;
  std::int64_t status_line = 0;
  std::string machine_state;
};

// A job of the daemon's queue (cncstreamd): created before it runs, so it
// has a row of its own; `journal_id` links it to the `jobs` row its run wrote.
// One tool change of a job: the tool in the spindle after it, the work
// offset's Z written (if any) and whether that tool's length is known.
struct ToolChangeRow {
  std::int64_t job_id = 0;
  std::int64_t line = 0;  // file line of the change
  std::int64_t tool = 0;
  std::string method;
  std::optional<double> offset_z;
  bool length_known = false;
  std::string note;
};

// A routine run outside a job (corner probing, the outline, the tool
// routines), as it ended: what it did or why it failed, and for a tool
// routine the tool left in the spindle and whether its length is known, so a
// later resume knows what changed since its job.
struct RoutineRow {
  std::string at;    // ISO 8601 UTC (set when recorded)
  std::string port;
  std::string name;
  bool succeeded = false;
  std::string text;
  bool tool_routine = false;  // the fields below are set
  std::int64_t tool = 0;
  std::string method;
  std::optional<double> offset_z;
  bool length_known = false;
};

struct DaemonJobRow {
  std::int64_t id = 0;
  std::string machine;
  std::string file_id;  // the upload's SHA-256
  std::string file_name;
  std::string kind;         // "stl" | "gcode"
  std::string params_json;  // the operation's parameters as given
  std::string state;        // queued, generating, ready, running, held, done, failed, stopped, interrupted, cancelled
  std::int64_t position = 0;
  std::string message;
  std::string created_at;
  std::optional<std::string> started_at, ended_at;
  std::int64_t journal_id = 0;
  std::int64_t resumed_from = 0;
  std::int64_t from_line = 0;
  std::int64_t last_line = 0;
  std::string tool_change_json;  // the job's own tool-change settings as given ("" none)
};

class Journal {
 public:
  // Opens or creates the database (and its folder).
  explicit Journal(const std::filesystem::path& path);
  ~Journal();
  Journal(const Journal&) = delete;
  Journal& operator=(const Journal&) = delete;

  // $XDG_STATE_HOME/cncstream/journal.sqlite, else ~/.local/state/cncstream/journal.sqlite.
  static std::filesystem::path default_path();
  const std::filesystem::path& path() const { return path_; }

  std::int64_t begin_job(const std::string& file, const std::string& sha256, const std::string& profile,
                         const std::string& port, const std::string& mode, std::int64_t total_lines,
                         std::int64_t resumed_from = 0, std::int64_t from_line = 0, std::int64_t planner_blocks = 0);
  void record_progress(const ProgressRecord& p);
  void end_job(std::int64_t job_id, const std::string& outcome, const std::string& message);
  void record_tool_change(const ToolChangeRow& r);
  std::vector<ToolChangeRow> tool_changes(std::int64_t job_id) const;
  void record_routine(const RoutineRow& r);
  // The routines on `port` recorded at or after `at` (ISO 8601), oldest first.
  std::vector<RoutineRow> routines_since(const std::string& at, const std::string& port) const;

  std::vector<JobRecord> jobs(int limit = 50) const;  // newest first
  std::optional<JobRecord> job(std::int64_t id) const;
  std::optional<ProgressRecord> last_progress(std::int64_t job_id) const;
  std::int64_t progress_count(std::int64_t job_id) const;
  // The last answered line of each of the job's rows with this reason, oldest first
  // ("error": the lines answered with an error).
  std::vector<std::int64_t> progress_lines(std::int64_t job_id, const std::string& reason) const;

  static std::string now_iso8601();

  // The daemon's queue and history (table daemon_jobs; journals of older
  // versions gain it when opened, and the CLI's tables are untouched).
  std::int64_t insert_daemon_job(const DaemonJobRow& row);  // returns the new id
  void update_daemon_job(const DaemonJobRow& row);
  std::vector<DaemonJobRow> daemon_jobs(int limit = 1000) const;  // unfinished first by position, then newest

 private:
  void exec(const char* sql);
  std::filesystem::path path_;
  sqlite3* db_ = nullptr;
};

}  // namespace cncstream::transport
