// Where the daemon journals: `journal` when set, else inside a given
// data_dir, else the CLI's journal.
#include <gtest/gtest.h>

#include "cncstream/daemon/config.hpp"
#include "cncstream/transport/journal.hpp"
#include "daemon_test_util.hpp"

using namespace dtest;
using cncstream::daemon::DaemonConfig;
using cncstream::daemon::journal_path;

TEST(DaemonJournal, DefaultsIntoTheDataDirWhenOneIsGiven) {
  DaemonConfig c;
  EXPECT_EQ(journal_path(c), cncstream::transport::Journal::default_path());
  c.data_dir = "/srv/cnc";
  EXPECT_EQ(journal_path(c), fs::path("/srv/cnc/journal.sqlite"));
  c.journal = "/var/lib/j.sqlite";
  EXPECT_EQ(journal_path(c), fs::path("/var/lib/j.sqlite"));
}

TEST(DaemonJournal, ADaemonWithADataDirKeepsItsJobsThere) {
  const auto dir = temp_dir("journal-default");
  auto cfg = test_config(dir);
  cfg.journal.clear();
  RunningDaemon d(cfg);
  const fs::path expected = cfg.data_dir / "journal.sqlite";
  EXPECT_EQ(d.daemon().config().journal, expected);
  Http h = d.http;
  h.headers["X-Client-Id"] = "journal-1";
  const auto f = h.request("POST", "/api/v1/files?name=line.nc", "G21\nG1 X1 F100\n",
                           {{"Content-Type", "application/octet-stream"}});
  ASSERT_EQ(f.status, 201) << f.body;
  const auto r = h.post("/api/v1/jobs", {{"machine", "sim1"}, {"file", f.j()["id"]}});
  ASSERT_EQ(r.status, 201) << r.body;
  ASSERT_TRUE(fs::exists(expected));
  cncstream::transport::Journal journal(expected);
  bool found = false;
  for (const auto& row : journal.daemon_jobs(100)) found |= row.id == r.j()["id"].get<std::int64_t>();
  EXPECT_TRUE(found) << "the job is not in " << expected;
  d.shutdown();
  fs::remove_all(dir);
}
