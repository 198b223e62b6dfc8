#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>

#include "cncstream/gcode/modal_words.hpp"
#include "cncstream/protocol/modal_state.hpp"
#include "cncstream/transport/journal.hpp"
#include "cncstream/transport/sha256.hpp"

using namespace cncstream::transport;
namespace fs = std::filesystem;

namespace {
fs::path temp_db(const char* name) {
  const auto dir = fs::temp_directory_path() / ("cncstream_journal_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const auto p = dir / name;
  for (const char* ext : {"", "-wal", "-shm"}) fs::remove(p.string() + ext);
  return p;
}
struct JournalCleanup : ::testing::Environment {
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(fs::temp_directory_path() / ("cncstream_journal_" + std::to_string(::getpid())), ec);
  }
};
const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new JournalCleanup);
}  // namespace

TEST(Sha256, KnownVectors) {
  EXPECT_EQ(sha256_hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256_hex(std::string(1000000, 'a')), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  EXPECT_EQ(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
}

TEST(Journal, RoundTrip) {
  const auto path = temp_db("round.sqlite");
  std::int64_t id = 0;
  {
    Journal j(path);
    id = j.begin_job("/parts/plate.nc", sha256_hex("G0X0\n"), "grbl-1.1", "/dev/ttyUSB0", "run", 1200);
    cncstream::gcode::ParserState m;
    cncstream::protocol::apply_answered_line(m, "G20G91G18G55F250S12000M3M8T2");
    ProgressRecord p;
    p.job_id = id;
    p.lines_ok = 10;
    p.last_line = 10;
    p.reason = "periodic";
    j.record_progress(p);
    p.lines_ok = 517;
    p.last_line = 518;
    p.reason = "error";
    p.modal = m;
    p.wco = std::array<double, 3>{1.5, -2.0, 3.25};
    p.status_work_pos = std::array<double, 3>{12.5, -3.25, -0.75};
    p.status_line = 511;
    p.machine_state = "Hold:0";
    j.record_progress(p);
    j.end_job(id, "error", "error:22 on line 519");
    EXPECT_THROW(j.end_job(id + 100, "x", "y"), JournalError);
  }
  Journal j(path);
  const auto jobs = j.jobs();
  ASSERT_EQ(jobs.size(), 1u);
  EXPECT_EQ(jobs[0].file, "/parts/plate.nc");
  EXPECT_EQ(jobs[0].total_lines, 1200);
  EXPECT_EQ(*jobs[0].outcome, "error");
  EXPECT_TRUE(jobs[0].ended_at);
  EXPECT_EQ(j.progress_count(id), 2);
  const auto last = j.last_progress(id);
  ASSERT_TRUE(last);
  EXPECT_EQ(last->lines_ok, 517);
  EXPECT_EQ(last->last_line, 518);
  EXPECT_EQ(last->reason, "error");
  const auto words = cncstream::gcode::modal_words(last->modal);
  EXPECT_EQ(words.units, "G20");
  EXPECT_EQ(words.distance, "G91");
  EXPECT_EQ(words.plane, "G18");
  EXPECT_EQ(words.wcs, "G55");
  EXPECT_DOUBLE_EQ(words.feed, 250);  // program units (inches per minute), as written
  EXPECT_NEAR(last->modal.feed_rate, 250 * 25.4, 1e-9);
  EXPECT_DOUBLE_EQ(words.spindle_speed, 12000);
  EXPECT_EQ(words.spindle, "M3");
  EXPECT_EQ(words.coolant, "M8");
  EXPECT_EQ(words.tool, 2);
  EXPECT_EQ(cncstream::gcode::format_modes(last->modal), "[GC:G0 G55 G18 G20 G91 G94 M3 M8 T2 F250 S12000]");
  ASSERT_TRUE(last->wco);
  EXPECT_DOUBLE_EQ((*last->wco)[2], 3.25);
  ASSERT_TRUE(last->status_work_pos);
  EXPECT_DOUBLE_EQ((*last->status_work_pos)[0], 12.5);
  EXPECT_DOUBLE_EQ((*last->status_work_pos)[2], -0.75);
  EXPECT_EQ(last->status_line, 511);
  EXPECT_EQ(last->machine_state, "Hold:0");
  EXPECT_FALSE(j.last_progress(id + 1));
}

TEST(Journal, AnOlderJournalGainsTheNewColumns) {
  const auto path = temp_db("old.sqlite");
  {
    // The progress table as the first version wrote it.
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
    const char* old_schema =
        "CREATE TABLE jobs (id INTEGER PRIMARY KEY AUTOINCREMENT, file TEXT NOT NULL, file_sha256 TEXT NOT NULL,"
        " profile TEXT NOT NULL, port TEXT NOT NULL, mode TEXT NOT NULL, total_lines INTEGER NOT NULL,"
        " started_at TEXT NOT NULL, ended_at TEXT, outcome TEXT, message TEXT NOT NULL DEFAULT '');"
        "CREATE TABLE progress (id INTEGER PRIMARY KEY AUTOINCREMENT, job_id INTEGER NOT NULL REFERENCES jobs(id),"
        " at TEXT NOT NULL, lines_ok INTEGER NOT NULL, last_line INTEGER NOT NULL, reason TEXT NOT NULL,"
        " units TEXT, distance TEXT, plane TEXT, wcs TEXT, motion TEXT, feed REAL, spindle_speed REAL,"
        " spindle TEXT, coolant TEXT, tool INTEGER, wco_x REAL, wco_y REAL, wco_z REAL);"
        "INSERT INTO jobs(file, file_sha256, profile, port, mode, total_lines, started_at)"
        " VALUES('/old.nc', 'ab', 'grbl-1.1', 'sim', 'run', 10, '2026-01-01T00:00:00.000Z');"
        "INSERT INTO progress(job_id, at, lines_ok, last_line, reason) VALUES(1, 'x', 4, 4, 'periodic');";
    ASSERT_EQ(sqlite3_exec(db, old_schema, nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
    sqlite3_close(db);
  }
  Journal j(path);
  const auto old_row = j.last_progress(1);
  ASSERT_TRUE(old_row);
  EXPECT_EQ(old_row->last_line, 4);
  EXPECT_FALSE(old_row->status_work_pos);
  ProgressRecord p;
  p.job_id = 1;
  p.last_line = 6;
  p.reason = "end";
  p.status_work_pos = std::array<double, 3>{1, 2, 3};
  p.status_line = 5;
  j.record_progress(p);
  ASSERT_TRUE(j.last_progress(1)->status_work_pos);
  EXPECT_EQ(j.last_progress(1)->status_line, 5);
}

TEST(Journal, AnOlderDaemonQueueGainsTheJobsToolChangeColumn) {
  const auto path = temp_db("old_queue.sqlite");
  {
    // daemon_jobs as it was before a job's tool-change settings were kept.
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
    const char* old_schema =
        "CREATE TABLE daemon_jobs (id INTEGER PRIMARY KEY AUTOINCREMENT, machine TEXT NOT NULL, file_id TEXT NOT NULL,"
        " file_name TEXT NOT NULL, kind TEXT NOT NULL, params TEXT NOT NULL, state TEXT NOT NULL,"
        " position INTEGER NOT NULL DEFAULT 0, message TEXT NOT NULL DEFAULT '', created_at TEXT NOT NULL,"
        " started_at TEXT, ended_at TEXT, journal_id INTEGER, resumed_from INTEGER NOT NULL DEFAULT 0,"
        " from_line INTEGER NOT NULL DEFAULT 0, last_line INTEGER NOT NULL DEFAULT 0);"
        "INSERT INTO daemon_jobs(machine, file_id, file_name, kind, params, state, created_at)"
        " VALUES('m', 'ab', 'a.nc', 'gcode', '', 'ready', '2026-01-01T00:00:00.000Z');";
    ASSERT_EQ(sqlite3_exec(db, old_schema, nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
    sqlite3_close(db);
  }
  Journal j(path);
  auto rows = j.daemon_jobs();
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].tool_change_json, "");
  DaemonJobRow r = rows[0];
  r.id = 0;
  r.tool_change_json = R"({"method":"controller"})";
  const auto id = j.insert_daemon_job(r);
  rows[0].tool_change_json = R"({"method":"sensor"})";
  j.update_daemon_job(rows[0]);
  for (const auto& row : j.daemon_jobs())
    EXPECT_EQ(row.tool_change_json, row.id == id ? R"({"method":"controller"})" : R"({"method":"sensor"})");
}

TEST(Journal, UnwritablePathNamesIt) {
  try {
    Journal j("/proc/cncstream/nope/journal.sqlite");
    FAIL();
  } catch (const JournalError& e) {
    EXPECT_NE(std::string(e.what()).find("/proc/cncstream/nope"), std::string::npos);
  }
}

TEST(Journal, SurvivesSigkillAtAnyMoment) {
  const auto path = temp_db("kill.sqlite");
  { Journal j(path); }  // create the schema before forking
  int pipefd[2];
  ASSERT_EQ(::pipe(pipefd), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::close(pipefd[0]);
    try {
      Journal j(path);
      const auto id = j.begin_job("kill.nc", sha256_hex("x"), "grbl-1.1", "pty", "run", 1000000);
      ProgressRecord p;
      p.job_id = id;
      p.reason = "periodic";
      for (std::int64_t i = 1;; ++i) {
        p.lines_ok = i;
        p.last_line = i;
        j.record_progress(p);
        // Report only what has been committed.
        if (::write(pipefd[1], &i, sizeof i) != sizeof i) ::_exit(3);
      }
    } catch (...) {
      ::_exit(2);
    }
  }
  ::close(pipefd[1]);
  std::int64_t committed = 0, v = 0;
  while (committed < 40 && ::read(pipefd[0], &v, sizeof v) == sizeof v) committed = v;
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  while (::read(pipefd[0], &v, sizeof v) == sizeof v) committed = v;  // drain what was reported before the kill
  ::close(pipefd[0]);
  ASSERT_TRUE(WIFSIGNALED(status));
  ASSERT_GE(committed, 40);

  Journal j(path);
  const auto jobs = j.jobs();
  ASSERT_EQ(jobs.size(), 1u);
  EXPECT_FALSE(jobs[0].outcome);  // never ended: shows as interrupted
  const auto last = j.last_progress(jobs[0].id);
  ASSERT_TRUE(last);
  EXPECT_GE(last->lines_ok, committed);  // every reported commit is there
  EXPECT_GE(j.progress_count(jobs[0].id), committed);
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  sqlite3_stmt* st = nullptr;
  sqlite3_prepare_v2(db, "PRAGMA integrity_check", -1, &st, nullptr);
  ASSERT_EQ(sqlite3_step(st), SQLITE_ROW);
  EXPECT_STREQ(reinterpret_cast<const char*>(sqlite3_column_text(st, 0)), "ok");
  sqlite3_finalize(st);
  sqlite3_close(db);
}

TEST(Journal, KeepsThePlannerDepthAndCountsRowsByReason) {
  const auto path = temp_db("planner.sqlite");
  Journal j(path);
  const auto id = j.begin_job("p.nc", sha256_hex("p"), "grblhal", "pty", "run", 10, 0, 0, 35);
  const auto old = j.begin_job("q.nc", sha256_hex("q"), "grbl-1.1", "pty", "run", 10);
  EXPECT_EQ(j.job(id)->planner_blocks, 35);
  EXPECT_EQ(j.job(old)->planner_blocks, 0) << "not journaled: unknown";
  ProgressRecord p;
  p.job_id = id;
  for (const char* reason : {"periodic", "error", "periodic", "error", "end"}) {
    p.reason = reason;
    ++p.last_line;
    j.record_progress(p);
  }
  EXPECT_EQ(j.progress_lines(id, "error"), (std::vector<std::int64_t>{2, 4}));
  EXPECT_EQ(j.progress_lines(id, "end"), (std::vector<std::int64_t>{5}));
  EXPECT_EQ(j.progress_count(id), 5);
}
