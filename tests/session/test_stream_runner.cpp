#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <filesystem>
#include <fstream>

#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/transport/journal.hpp"
#include "cncstream/transport/serial_transport.hpp"
#include "cncstream/session/simulator_port.hpp"
#include "cncstream/session/stream_runner.hpp"
#include "fake_grbl.hpp"
#include "fake_marlin.hpp"

using namespace cncstream::transport;
using namespace cncstream::session;
using cncstream::protocol::JobOutcome;
namespace fs = std::filesystem;

namespace {

fs::path temp_dir() {
  const auto d = fs::temp_directory_path() / ("cncstream_pty_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

fs::path write_program(const std::string& name, int lines) {
  const auto p = temp_dir() / name;
  std::ofstream out(p);
  out << "(test program)\nG21 G90\n";
  for (int i = 0; i < lines; ++i) out << "G1 X" << i % 97 << "." << i % 1000 << " Y" << (i * 7) % 13 << " F1200 ; seg\n";
  out << "M2\n";
  return p;
}

RunnerOptions options(FakeGrbl& fake, const fs::path& journal) {
  RunnerOptions o;
  o.port = fake.slave_path();
  o.profiles_dir = CNCSTREAM_SOURCE_DIR "/firmware-profiles";
  o.journal_path = journal;
  o.identify.banner_timeout_s = 2;
  o.max_run_s = 30;
  o.on_port_opened = [&fake] { fake.reset(); };
  o.read_settings = false;  // the fake counts every line it answers; `$$` is covered against cncsim
  return o;
}

// Removes the per-process temp folder when the test program ends.
struct TempCleanup : ::testing::Environment {
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(fs::temp_directory_path() / ("cncstream_pty_" + std::to_string(::getpid())), ec);
  }
};
const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new TempCleanup);

}  // namespace

TEST(SerialPty, ExchangesBytesAndReportsDisconnectAtOnce) {
  FakeGrbl fake;
  fake.start();
  boost::asio::io_context io;
  SerialTransport t(io, SerialSettings{});
  t.open(fake.slave_path());
  std::string got;
  std::string closed;
  t.start([&](std::string_view b) {
    got.append(b);
    if (got.find("Grbl 1.1h") != std::string::npos && got.find("ok") == std::string::npos) t.write("G0X1\n");
  }, [&](const std::string& why) { closed = why; });
  fake.disconnect_after = 1;
  fake.reset();
  boost::asio::steady_timer guard(io, std::chrono::seconds(5));
  guard.async_wait([&](auto) { t.close(); });
  io.run_one_for(std::chrono::seconds(5));
  while (closed.empty() && !io.stopped() && io.run_one_for(std::chrono::seconds(5)) > 0) {
  }
  EXPECT_NE(got.find("ok"), std::string::npos) << got;
  EXPECT_FALSE(closed.empty());  // EIO/EOF on the slave once the master is gone
  EXPECT_EQ(fake.received(), std::vector<std::string>{"G0X1"});
}

TEST(SerialPty, OpenErrorNamesThePath) {
  boost::asio::io_context io;
  SerialTransport t(io, SerialSettings{});
  try {
    t.open("/dev/cncstream-no-such-port");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/cncstream-no-such-port"), std::string::npos);
  }
}

TEST(StreamRunner, StreamsAJobOverAPtyAndJournalsIt) {
  FakeGrbl fake;
  fake.start();
  const auto prog = write_program("job.nc", 400);
  const auto db = temp_dir() / "journal1.sqlite";
  for (const char* ext : {"", "-wal", "-shm"}) fs::remove(db.string() + ext);
  auto o = options(fake, db);
  StreamRunner r(o);
  const auto res = r.run(prog);
  EXPECT_EQ(res.outcome, JobOutcome::Completed) << res.message;
  EXPECT_EQ(res.profile, "grbl-1.1");
  EXPECT_FALSE(fake.overflowed());
  EXPECT_GT(fake.max_rx(), 64u);  // the buffer was kept full, not one line at a time
  EXPECT_EQ(fake.answered(), 402);
  Journal j(db);
  const auto jobs = j.jobs();
  ASSERT_EQ(jobs.size(), 1u);
  EXPECT_EQ(*jobs[0].outcome, "completed");
  EXPECT_EQ(jobs[0].total_lines, 403);
  const auto last = j.last_progress(jobs[0].id);
  ASSERT_TRUE(last);
  EXPECT_EQ(last->lines_ok, 403);
  EXPECT_DOUBLE_EQ(last->modal.feed_rate, 1200);
}

TEST(StreamRunner, DisconnectRecordsTheLastAnsweredLine) {
  FakeGrbl fake;
  fake.lines_per_step = 1;
  fake.disconnect_after = 120;
  fake.start();
  const auto prog = write_program("cut.nc", 400);
  const auto db = temp_dir() / "journal2.sqlite";
  for (const char* ext : {"", "-wal", "-shm"}) fs::remove(db.string() + ext);
  StreamRunner r(options(fake, db));
  const auto res = r.run(prog);
  EXPECT_EQ(res.outcome, JobOutcome::Disconnected) << res.message;
  // 120 G-code lines answered: file lines 2..121 (line 1 is a comment).
  EXPECT_EQ(res.last_answered_line, 121);
  Journal j(db);
  const auto jobs = j.jobs();
  ASSERT_EQ(jobs.size(), 1u);
  EXPECT_EQ(*jobs[0].outcome, "disconnected");
  EXPECT_EQ(j.last_progress(jobs[0].id)->last_line, 121);
}

TEST(StreamRunner, ErrorHoldsThenStopResetsCleanly) {
  FakeGrbl fake;
  fake.errors[30] = 20;  // the 30th G-code line is refused
  fake.lines_per_step = 1;
  fake.start();
  const auto prog = write_program("err.nc", 200);
  const auto db = temp_dir() / "journal3.sqlite";
  for (const char* ext : {"", "-wal", "-shm"}) fs::remove(db.string() + ext);
  auto o = options(fake, db);
  StreamRunner* runner = nullptr;
  std::vector<cncstream::protocol::Event> errors;
  o.on_event = [&](const cncstream::protocol::Event& e) {
    if (e.kind == cncstream::protocol::EventKind::LineError) {
      errors.push_back(e);
      runner->request_stop();  // the operator chooses to stop
    }
  };
  StreamRunner r(o);
  runner = &r;
  const auto res = r.run(prog);
  EXPECT_EQ(res.outcome, JobOutcome::Error) << res.message;
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0].source_line, 31);
  EXPECT_EQ(errors[0].code, 20);
  EXPECT_EQ(fake.resets(), 2);  // the opening reset and our soft reset after Hold:0
  Journal j(db);
  const auto jobs = j.jobs();
  EXPECT_EQ(*jobs[0].outcome, "error");
  EXPECT_GE(j.progress_count(jobs[0].id), 2);
}

TEST(StreamRunner, MarlinWithChecksumsAndAForcedResend) {
  FakeMarlin fake;
  fake.corrupt_once = 7;
  fake.start();
  const auto prog = write_program("marlin.gcode", 60);
  const auto db = temp_dir() / "journal4.sqlite";
  for (const char* ext : {"", "-wal", "-shm"}) fs::remove(db.string() + ext);
  RunnerOptions o;
  o.port = fake.slave_path();
  o.profiles_dir = CNCSTREAM_SOURCE_DIR "/firmware-profiles";
  o.journal_path = db;
  o.max_run_s = 30;
  o.on_port_opened = [&fake] { fake.reset(); };
  StreamRunner r(o);
  const auto res = r.run(prog);
  EXPECT_EQ(res.outcome, JobOutcome::Completed) << res.message;
  EXPECT_EQ(res.profile, "marlin");
  EXPECT_EQ(fake.bad_checksums(), 1);
  EXPECT_EQ(fake.accepted(), 62);  // G21 G90, 60 moves, M2: each accepted once, in order
}

TEST(StreamRunner, OverridesReachTheControllerDuringAJob) {
  FakeGrbl fake;
  fake.lines_per_step = 1;
  fake.start();
  const auto prog = write_program("ov.nc", 300);
  auto o = options(fake, temp_dir() / "journal5.sqlite");
  o.journal_path.reset();
  StreamRunner* runner = nullptr;
  bool sent = false;
  std::vector<std::string> warnings;
  o.on_event = [&](const cncstream::protocol::Event& e) {
    using cncstream::protocol::EventKind;
    using cncstream::protocol::Realtime;
    if (e.kind == EventKind::Warning) warnings.push_back(e.text);
    if (e.kind == EventKind::LineAnswered && !sent) {
      sent = true;
      runner->request_realtime(Realtime::FeedOvPlus10);
      runner->request_realtime(Realtime::SpindleOvMinus10);
      runner->request_realtime(Realtime::ToolChangeAck);  // grblHAL only: refused for GRBL 1.1
    }
  };
  StreamRunner r(o);
  runner = &r;
  const auto res = r.run(prog);
  EXPECT_EQ(res.outcome, JobOutcome::Completed) << res.message;
  EXPECT_EQ(fake.realtime_seen(), "\x91\x9b");
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("tool_change_ack"), std::string::npos);
}

// A runner that gives up (--timeout) with the job still running used to
// report "0 lines answered, last answered file line 0" and end the journaled
// job without an end row. Here the last line's end of line is lost on the
// wire, so the job can never end by itself.
TEST(StreamRunner, GivingUpSaysHowFarTheJobGotAndJournalsItsEnd) {
  const auto prog = temp_dir() / "lost_eol.nc";
  std::ofstream(prog) << "G21 G90\nG1 X1 F500\nG1 X2\nG1 X3\n";
  SimulatorOptions so;
  so.faults.drop_byte_at[2 + 4] = cncsim::ByteOfLine::end_of_line();  // after $I and $$: the 4th file line
  const auto sim = std::make_shared<SimulatorPort>(so);
  RunnerOptions o;
  o.machine_port = sim;
  o.profiles_dir = CNCSTREAM_SOURCE_DIR "/firmware-profiles";
  const auto journal = temp_dir() / "gave_up.sqlite";
  o.journal_path = journal;
  o.max_run_s = 1.5;
  StreamRunner runner(o);
  const RunResult r = runner.run(prog);
  EXPECT_EQ(r.outcome, JobOutcome::Error);
  EXPECT_EQ(r.message, "gave up after 1.5 s");
  EXPECT_EQ(r.lines_answered, 3u);
  EXPECT_EQ(r.last_answered_line, 3);
  Journal j(journal);
  const auto job = j.job(r.job_id);
  ASSERT_TRUE(job);
  EXPECT_EQ(job->outcome.value_or(""), "error");
  const auto last = j.last_progress(r.job_id);
  ASSERT_TRUE(last);
  EXPECT_EQ(last->reason, "end");
  EXPECT_EQ(last->last_line, 3);
  sim->finish(false);
}

// An error row names the line that failed. It used to take the last answered
// line when the event was delivered, which could already be lines further
// on when more answers came in the same read (found by the soak: a resume
// then skipped the failed line).
TEST(StreamRunner, AnErrorRowNamesTheLineThatFailed) {
  const auto prog = temp_dir() / "error_row.nc";
  {
    std::ofstream f(prog);
    f << "G21 G90 F3000\n";
    for (int i = 1; i <= 30; ++i) f << "G1 X" << i % 7 << " Y" << i % 5 << "\n";
  }
  SimulatorOptions so;
  so.faults.error_at[2 + 4] = 20;  // after $I and $$: file line 4
  const auto sim = std::make_shared<SimulatorPort>(so);
  RunnerOptions o;
  o.machine_port = sim;
  o.profiles_dir = CNCSTREAM_SOURCE_DIR "/firmware-profiles";
  const auto journal = temp_dir() / "error_row.sqlite";
  o.journal_path = journal;
  o.max_run_s = 20;
  StreamRunner* self = nullptr;
  o.on_event = [&self](const cncstream::protocol::Event& e) {
    if (e.kind == cncstream::protocol::EventKind::LineError && self) self->request_stop();
  };
  StreamRunner runner(o);
  self = &runner;
  const RunResult r = runner.run(prog);
  EXPECT_EQ(r.outcome, JobOutcome::Error);
  Journal j(journal);
  EXPECT_EQ(j.progress_lines(r.job_id, "error"), (std::vector<std::int64_t>{4}));
  EXPECT_GE(j.last_progress(r.job_id)->last_line, 4);
  sim->finish(false);
}
