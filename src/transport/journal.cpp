#include "cncstream/transport/journal.hpp"

#include <fmt/core.h>

#include "cncstream/gcode/modal_words.hpp"

#include <sqlite3.h>

#include <chrono>
#include <cstdlib>
#include <initializer_list>
#include <ctime>
#include <string>

namespace cncstream::transport {

namespace {

// RAII statement with bind helpers; errors name the database file.
class Stmt {
 public:
  Stmt(sqlite3* db, const std::filesystem::path& path, const char* sql) : db_(db), path_(path) {
    if (sqlite3_prepare_v2(db, sql, -1, &s_, nullptr) != SQLITE_OK) fail("prepare");
  }
  ~Stmt() { sqlite3_finalize(s_); }
  Stmt(const Stmt&) = delete;
  Stmt& operator=(const Stmt&) = delete;
  Stmt& bind(int i, const std::string& v) {
    sqlite3_bind_text(s_, i, v.c_str(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
    return *this;
  }
  Stmt& bind(int i, std::int64_t v) {
    sqlite3_bind_int64(s_, i, v);
    return *this;
  }
  Stmt& bind(int i, double v) {
    sqlite3_bind_double(s_, i, v);
    return *this;
  }
  Stmt& bind_null(int i) {
    sqlite3_bind_null(s_, i);
    return *this;
  }
  bool step() {
    const int rc = sqlite3_step(s_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    fail("step");
  }
  std::string text(int c) const {
    const auto* p = sqlite3_column_text(s_, c);
    return p ? reinterpret_cast<const char*>(p) : "";
  }
  std::optional<std::string> opt_text(int c) const {
    if (sqlite3_column_type(s_, c) == SQLITE_NULL) return std::nullopt;
    return text(c);
  }
  std::int64_t i64(int c) const { return sqlite3_column_int64(s_, c); }
  double f64(int c) const { return sqlite3_column_double(s_, c); }
  bool is_null(int c) const { return sqlite3_column_type(s_, c) == SQLITE_NULL; }

 private:
  [[noreturn]] void fail(const char* what) {
    throw JournalError(path_.string() + ": SQLite " + what + " failed: " + sqlite3_errmsg(db_));
  }
  sqlite3* db_;
  const std::filesystem::path& path_;
  sqlite3_stmt* s_ = nullptr;
};

JobRecord read_job(const Stmt& s) {
  JobRecord j;
  j.id = s.i64(0);
  j.file = s.text(1);
  j.file_sha256 = s.text(2);
  j.profile = s.text(3);
  j.port = s.text(4);
  j.mode = s.text(5);
  j.total_lines = s.i64(6);
  j.started_at = s.text(7);
  j.ended_at = s.opt_text(8);
  j.outcome = s.opt_text(9);
  j.message = s.text(10);
  j.resumed_from = s.is_null(11) ? 0 : s.i64(11);
  j.from_line = s.is_null(12) ? 0 : s.i64(12);
  j.planner_blocks = s.is_null(13) ? 0 : s.i64(13);
  return j;
}

constexpr const char* kJobColumns =
    "id, file, file_sha256, profile, port, mode, total_lines, started_at, ended_at, outcome, message,"
    " resumed_from, from_line, planner_blocks";

}  // namespace

Journal::Journal(const std::filesystem::path& path) : path_(path) {
  std::error_code ec;
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path(), ec);
  if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX,
                      nullptr) != SQLITE_OK) {
    const std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw JournalError(path.string() + ": cannot open journal: " + msg);
  }
  sqlite3_busy_timeout(db_, 2000);
  try {
    // WAL: a commit is one append to the log; FULL: it is fsynced before the
    // commit returns, so a kill (or power loss) loses nothing committed.
    exec("PRAGMA journal_mode=WAL");
    exec("PRAGMA synchronous=FULL");
    exec("PRAGMA foreign_keys=ON");
    exec("CREATE TABLE IF NOT EXISTS jobs ("
         " id INTEGER PRIMARY KEY AUTOINCREMENT, file TEXT NOT NULL, file_sha256 TEXT NOT NULL,"
         " profile TEXT NOT NULL, port TEXT NOT NULL, mode TEXT NOT NULL, total_lines INTEGER NOT NULL,"
         " started_at TEXT NOT NULL, ended_at TEXT, outcome TEXT, message TEXT NOT NULL DEFAULT '')");
    // Columns added later: a journal from an older version gains them here.
    const auto add_columns = [&](const char* table, std::initializer_list<const char*> adds) {
      for (const char* add : adds)
        if (sqlite3_exec(db_, add, nullptr, nullptr, nullptr) != SQLITE_OK &&
            std::string(sqlite3_errmsg(db_)).find("duplicate column") == std::string::npos)
          throw JournalError(path.string() + ": cannot upgrade the " + table + " table: " + sqlite3_errmsg(db_));
    };
    add_columns("jobs", {"ALTER TABLE jobs ADD COLUMN resumed_from INTEGER", "ALTER TABLE jobs ADD COLUMN from_line INTEGER",
                         "ALTER TABLE jobs ADD COLUMN planner_blocks INTEGER"});
    exec("CREATE TABLE IF NOT EXISTS progress ("
         " id INTEGER PRIMARY KEY AUTOINCREMENT, job_id INTEGER NOT NULL REFERENCES jobs(id),"
         " at TEXT NOT NULL, lines_ok INTEGER NOT NULL, last_line INTEGER NOT NULL, reason TEXT NOT NULL,"
         " units TEXT, distance TEXT, plane TEXT, wcs TEXT, motion TEXT, feed REAL, spindle_speed REAL,"
         " spindle TEXT, coolant TEXT, tool INTEGER, wco_x REAL, wco_y REAL, wco_z REAL)");
    add_columns("progress", {"ALTER TABLE progress ADD COLUMN status_x REAL", "ALTER TABLE progress ADD COLUMN status_y REAL",
                             "ALTER TABLE progress ADD COLUMN status_z REAL",
                             "ALTER TABLE progress ADD COLUMN status_line INTEGER",
                             "ALTER TABLE progress ADD COLUMN machine_state TEXT"});
    exec("CREATE INDEX IF NOT EXISTS progress_job ON progress(job_id, id)");
    // Tool changes a job made: which tool is in the spindle after each and
    // whether its length is known (resume reads the last one).
    exec("CREATE TABLE IF NOT EXISTS tool_changes ("
         " id INTEGER PRIMARY KEY AUTOINCREMENT, job_id INTEGER NOT NULL REFERENCES jobs(id), at TEXT NOT NULL,"
         " line INTEGER NOT NULL, tool INTEGER NOT NULL, method TEXT NOT NULL, offset_z REAL,"
         " length_known INTEGER NOT NULL, note TEXT NOT NULL)");
    // Routines outside a job: a new table (older journals gain it when opened).
    exec("CREATE TABLE IF NOT EXISTS routines ("
         " id INTEGER PRIMARY KEY AUTOINCREMENT, at TEXT NOT NULL, port TEXT NOT NULL, name TEXT NOT NULL,"
         " succeeded INTEGER NOT NULL, text TEXT NOT NULL, tool INTEGER, method TEXT, offset_z REAL, length_known INTEGER)");
    // cncstreamd's queue: a new table, so older journals stay readable by
    // older programs and gain it the first time the daemon opens them.
    exec("CREATE TABLE IF NOT EXISTS daemon_jobs ("
         " id INTEGER PRIMARY KEY AUTOINCREMENT, machine TEXT NOT NULL, file_id TEXT NOT NULL, file_name TEXT NOT NULL,"
         " kind TEXT NOT NULL, params TEXT NOT NULL, state TEXT NOT NULL, position INTEGER NOT NULL DEFAULT 0,"
         " message TEXT NOT NULL DEFAULT '', created_at TEXT NOT NULL, started_at TEXT, ended_at TEXT,"
         " journal_id INTEGER, resumed_from INTEGER NOT NULL DEFAULT 0, from_line INTEGER NOT NULL DEFAULT 0,"
         " last_line INTEGER NOT NULL DEFAULT 0)");
    // A job's own tool-change settings (its JSON as given, '' none); older
    // programs name their columns and pass it over.
    add_columns("daemon_jobs", {"ALTER TABLE daemon_jobs ADD COLUMN tool_change TEXT NOT NULL DEFAULT ''"});
  } catch (...) {
    sqlite3_close(db_);
    db_ = nullptr;
    throw;
  }
}

Journal::~Journal() { sqlite3_close(db_); }

void Journal::exec(const char* sql) {
  char* err = nullptr;
  if (sqlite3_exec(db_, sql, nullptr, nullptr, &err) != SQLITE_OK) {
    const std::string msg = err ? err : "unknown error";
    sqlite3_free(err);
    throw JournalError(path_.string() + ": " + msg + " (in: " + sql + ")");
  }
}

std::filesystem::path Journal::default_path() {
  if (const char* s = std::getenv("XDG_STATE_HOME"); s && *s)
    return std::filesystem::path(s) / "cncstream" / "journal.sqlite";
  if (const char* h = std::getenv("HOME"); h && *h)
    return std::filesystem::path(h) / ".local" / "state" / "cncstream" / "journal.sqlite";
  return std::filesystem::path("cncstream-journal.sqlite");
}

std::string Journal::now_iso8601() {
  const auto now = std::chrono::system_clock::now();
  const auto t = std::chrono::system_clock::to_time_t(now);
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[40];
  const std::size_t n = std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);  // 19 characters, never 0
  return fmt::format("{}.{:03}Z", std::string_view(buf, n), static_cast<int>(ms));
}

std::int64_t Journal::begin_job(const std::string& file, const std::string& sha256, const std::string& profile,
                                const std::string& port, const std::string& mode, std::int64_t total_lines,
                                std::int64_t resumed_from, std::int64_t from_line, std::int64_t planner_blocks) {
  Stmt s(db_, path_,
         "INSERT INTO jobs(file, file_sha256, profile, port, mode, total_lines, started_at, resumed_from, from_line,"
         " planner_blocks) VALUES(?,?,?,?,?,?,?,?,?,?)");
  s.bind(1, file).bind(2, sha256).bind(3, profile).bind(4, port).bind(5, mode).bind(6, total_lines).bind(7, now_iso8601());
  if (resumed_from > 0) s.bind(8, resumed_from).bind(9, from_line);
  else s.bind_null(8).bind_null(9);
  if (planner_blocks > 0) s.bind(10, planner_blocks);
  else s.bind_null(10);
  s.step();
  return sqlite3_last_insert_rowid(db_);
}

void Journal::record_progress(const ProgressRecord& p) {
  Stmt s(db_, path_,
         "INSERT INTO progress(job_id, at, lines_ok, last_line, reason, units, distance, plane, wcs, motion, feed,"
         " spindle_speed, spindle, coolant, tool, wco_x, wco_y, wco_z, status_x, status_y, status_z, status_line,"
         " machine_state) VALUES(?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?)");
  const gcode::ModalWords m = gcode::modal_words(p.modal);
  s.bind(1, p.job_id).bind(2, p.at.empty() ? now_iso8601() : p.at).bind(3, p.lines_ok).bind(4, p.last_line);
  s.bind(5, p.reason).bind(6, m.units).bind(7, m.distance).bind(8, m.plane).bind(9, m.wcs).bind(10, m.motion);
  s.bind(11, m.feed).bind(12, m.spindle_speed).bind(13, m.spindle).bind(14, m.coolant);
  s.bind(15, static_cast<std::int64_t>(m.tool));
  if (p.wco) s.bind(16, (*p.wco)[0]).bind(17, (*p.wco)[1]).bind(18, (*p.wco)[2]);
  else s.bind_null(16).bind_null(17).bind_null(18);
  if (p.status_work_pos) s.bind(19, (*p.status_work_pos)[0]).bind(20, (*p.status_work_pos)[1]).bind(21, (*p.status_work_pos)[2]);
  else s.bind_null(19).bind_null(20).bind_null(21);
  s.bind(22, p.status_line).bind(23, p.machine_state);
  s.step();
}

void Journal::record_tool_change(const ToolChangeRow& r) {
  Stmt s(db_, path_,
         "INSERT INTO tool_changes (job_id, at, line, tool, method, offset_z, length_known, note) VALUES (?,?,?,?,?,?,?,?)");
  s.bind(1, r.job_id).bind(2, now_iso8601()).bind(3, r.line).bind(4, r.tool).bind(5, r.method);
  if (r.offset_z) s.bind(6, *r.offset_z);
  else s.bind_null(6);
  s.bind(7, static_cast<std::int64_t>(r.length_known ? 1 : 0)).bind(8, r.note);
  s.step();
}

void Journal::record_routine(const RoutineRow& r) {
  Stmt s(db_, path_,
         "INSERT INTO routines (at, port, name, succeeded, text, tool, method, offset_z, length_known)"
         " VALUES (?,?,?,?,?,?,?,?,?)");
  s.bind(1, now_iso8601()).bind(2, r.port).bind(3, r.name).bind(4, static_cast<std::int64_t>(r.succeeded ? 1 : 0));
  s.bind(5, r.text);
  if (r.tool_routine) {
    s.bind(6, r.tool).bind(7, r.method);
    if (r.offset_z) s.bind(8, *r.offset_z);
    else s.bind_null(8);
    s.bind(9, static_cast<std::int64_t>(r.length_known ? 1 : 0));
  } else {
    s.bind_null(6).bind_null(7).bind_null(8).bind_null(9);
  }
  s.step();
}

std::vector<RoutineRow> Journal::routines_since(const std::string& at, const std::string& port) const {
  Stmt s(db_, path_,
         "SELECT at, port, name, succeeded, text, tool, method, offset_z, length_known FROM routines"
         " WHERE at >= ? AND port = ? ORDER BY id");
  s.bind(1, at).bind(2, port);
  std::vector<RoutineRow> out;
  while (s.step()) {
    RoutineRow r;
    r.at = s.text(0);
    r.port = s.text(1);
    r.name = s.text(2);
    r.succeeded = s.i64(3) != 0;
    r.text = s.text(4);
    r.tool_routine = !s.is_null(5);
    if (r.tool_routine) {
      r.tool = s.i64(5);
      r.method = s.text(6);
      if (!s.is_null(7)) r.offset_z = s.f64(7);
      r.length_known = s.i64(8) != 0;
    }
    out.push_back(std::move(r));
  }
  return out;
}

std::vector<ToolChangeRow> Journal::tool_changes(std::int64_t job_id) const {
  Stmt s(db_, path_,
         "SELECT job_id, line, tool, method, offset_z, length_known, note FROM tool_changes WHERE job_id=? ORDER BY id");
  s.bind(1, job_id);
  std::vector<ToolChangeRow> out;
  while (s.step()) {
    ToolChangeRow r;
    r.job_id = s.i64(0);
    r.line = s.i64(1);
    r.tool = s.i64(2);
    r.method = s.text(3);
    if (!s.is_null(4)) r.offset_z = s.f64(4);
    r.length_known = s.i64(5) != 0;
    r.note = s.text(6);
    out.push_back(std::move(r));
  }
  return out;
}

void Journal::end_job(std::int64_t job_id, const std::string& outcome, const std::string& message) {
  Stmt s(db_, path_, "UPDATE jobs SET ended_at=?, outcome=?, message=? WHERE id=?");
  s.bind(1, now_iso8601()).bind(2, outcome).bind(3, message).bind(4, job_id);
  s.step();
  if (sqlite3_changes(db_) != 1) throw JournalError(path_.string() + ": no job " + std::to_string(job_id) + " to end");
}

std::vector<JobRecord> Journal::jobs(int limit) const {
  Stmt s(db_, path_, (std::string("SELECT ") + kJobColumns + " FROM jobs ORDER BY id DESC LIMIT ?").c_str());
  s.bind(1, static_cast<std::int64_t>(limit));
  std::vector<JobRecord> out;
  while (s.step()) out.push_back(read_job(s));
  return out;
}

std::optional<JobRecord> Journal::job(std::int64_t id) const {
  Stmt s(db_, path_, (std::string("SELECT ") + kJobColumns + " FROM jobs WHERE id=?").c_str());
  s.bind(1, id);
  if (!s.step()) return std::nullopt;
  return read_job(s);
}

std::optional<ProgressRecord> Journal::last_progress(std::int64_t job_id) const {
  Stmt s(db_, path_,
         "SELECT job_id, at, lines_ok, last_line, reason, units, distance, plane, wcs, motion, feed, spindle_speed,"
         " spindle, coolant, tool, wco_x, wco_y, wco_z, status_x, status_y, status_z, status_line, machine_state"
         " FROM progress WHERE job_id=? ORDER BY id DESC LIMIT 1");
  s.bind(1, job_id);
  if (!s.step()) return std::nullopt;
  ProgressRecord p;
  p.job_id = s.i64(0);
  p.at = s.text(1);
  p.lines_ok = s.i64(2);
  p.last_line = s.i64(3);
  p.reason = s.text(4);
  gcode::ModalWords m;
  m.units = s.text(5);
  m.distance = s.text(6);
  m.plane = s.text(7);
  m.wcs = s.text(8);
  m.motion = s.text(9);
  m.feed = s.f64(10);
  m.spindle_speed = s.f64(11);
  m.spindle = s.text(12);
  m.coolant = s.text(13);
  m.tool = static_cast<int>(s.i64(14));
  try {
    p.modal = gcode::modal_from_words(m);
  } catch (const std::invalid_argument& e) {
    throw JournalError(path_.string() + ": job " + std::to_string(job_id) + ": " + e.what());
  }
  if (!s.is_null(15)) p.wco = std::array<double, 3>{s.f64(15), s.f64(16), s.f64(17)};
  if (!s.is_null(18)) p.status_work_pos = std::array<double, 3>{s.f64(18), s.f64(19), s.f64(20)};
  if (!s.is_null(21)) p.status_line = s.i64(21);
  if (!s.is_null(22)) p.machine_state = s.text(22);
  return p;
}

std::vector<std::int64_t> Journal::progress_lines(std::int64_t job_id, const std::string& reason) const {
  Stmt s(db_, path_, "SELECT last_line FROM progress WHERE job_id=? AND reason=? ORDER BY id");
  s.bind(1, job_id).bind(2, reason);
  std::vector<std::int64_t> out;
  while (s.step()) out.push_back(s.i64(0));
  return out;
}

std::int64_t Journal::progress_count(std::int64_t job_id) const {
  Stmt s(db_, path_, "SELECT COUNT(*) FROM progress WHERE job_id=?");
  s.bind(1, job_id);
  s.step();
  return s.i64(0);
}

namespace {

constexpr const char* kDaemonJobColumns =
    "id, machine, file_id, file_name, kind, params, state, position, message, created_at, started_at, ended_at,"
    " journal_id, resumed_from, from_line, last_line, tool_change";

void bind_daemon_job(Stmt& s, const DaemonJobRow& r) {
  s.bind(1, r.machine).bind(2, r.file_id).bind(3, r.file_name).bind(4, r.kind).bind(5, r.params_json).bind(6, r.state);
  s.bind(7, r.position).bind(8, r.message).bind(9, r.created_at);
  if (r.started_at) s.bind(10, *r.started_at);
  else s.bind_null(10);
  if (r.ended_at) s.bind(11, *r.ended_at);
  else s.bind_null(11);
  if (r.journal_id) s.bind(12, r.journal_id);
  else s.bind_null(12);
  s.bind(13, r.resumed_from).bind(14, r.from_line).bind(15, r.last_line).bind(16, r.tool_change_json);
}

}  // namespace

std::int64_t Journal::insert_daemon_job(const DaemonJobRow& r) {
  Stmt s(db_, path_,
         "INSERT INTO daemon_jobs (machine, file_id, file_name, kind, params, state, position, message, created_at,"
         " started_at, ended_at, journal_id, resumed_from, from_line, last_line, tool_change)"
         " VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16)");
  bind_daemon_job(s, r);
  s.step();
  return sqlite3_last_insert_rowid(db_);
}

void Journal::update_daemon_job(const DaemonJobRow& r) {
  Stmt s(db_, path_,
         "UPDATE daemon_jobs SET machine=?1, file_id=?2, file_name=?3, kind=?4, params=?5, state=?6, position=?7,"
         " message=?8, created_at=?9, started_at=?10, ended_at=?11, journal_id=?12, resumed_from=?13, from_line=?14,"
         " last_line=?15, tool_change=?16 WHERE id=?17");
  bind_daemon_job(s, r);
  s.bind(17, r.id);
  s.step();
}

std::vector<DaemonJobRow> Journal::daemon_jobs(int limit) const {
  const std::string sql = std::string("SELECT ") + kDaemonJobColumns +
                          " FROM daemon_jobs ORDER BY (ended_at IS NOT NULL), position, id DESC LIMIT ?1";
  Stmt s(db_, path_, sql.c_str());
  s.bind(1, static_cast<std::int64_t>(limit));
  std::vector<DaemonJobRow> out;
  while (s.step()) {
    DaemonJobRow r;
    r.id = s.i64(0);
    r.machine = s.text(1);
    r.file_id = s.text(2);
    r.file_name = s.text(3);
    r.kind = s.text(4);
    r.params_json = s.text(5);
    r.state = s.text(6);
    r.position = s.i64(7);
    r.message = s.text(8);
    r.created_at = s.text(9);
    r.started_at = s.opt_text(10);
    r.ended_at = s.opt_text(11);
    r.journal_id = s.is_null(12) ? 0 : s.i64(12);
    r.resumed_from = s.i64(13);
    r.from_line = s.i64(14);
    r.last_line = s.i64(15);
    r.tool_change_json = s.text(16);
    out.push_back(std::move(r));
  }
  return out;
}

}  // namespace cncstream::transport
