// The hub's schema, its roles and claiming, against a throw-away PostgreSQL.
#include <gtest/gtest.h>

#include <atomic>
#include <map>
#include <mutex>
#include <set>
#include <thread>

#include "cncstream/shop/hub.hpp"
#include "cncstream/shop/schema.hpp"
#include "shop_test_util.hpp"

using namespace cncstream::shop;

namespace {

MachineInfo machine(const std::string& name, std::vector<std::string> caps = {}) {
  MachineInfo m;
  m.name = name;
  m.pc = "pc-test";
  m.profile = "grbl-1.1";
  m.travel_mm = std::array<double, 3>{300, 300, 80};
  m.capabilities = std::move(caps);
  return m;
}

Submission gcode_job(const std::string& name, std::vector<std::string> needs = {}, std::string only = {}) {
  Submission s;
  s.file_name = name;
  s.kind = "gcode";
  s.content = "G21\nG90\nG0 X1\n";
  s.needs = std::move(needs);
  s.machine = std::move(only);
  return s;
}

}  // namespace

TEST(ShopSchema, InitCreatesThenMigratesNothingTheSecondTime) {
  SHOP_REQUIRE_POSTGRES();
  shoptest::TempPostgres pg;
  PgConnection db(pg.create_database("schema1"));
  EXPECT_EQ(hub_schema_version(db), 0);
  const auto first = migrate(db);
  EXPECT_EQ(first.from, 0);
  EXPECT_EQ(first.to, schema_version_known());
  const auto again = migrate(db);
  EXPECT_EQ(again.from, schema_version_known());
  EXPECT_EQ(again.to, schema_version_known());
  // The tables are there and empty.
  for (const char* t : {"machines", "machine_state", "jobs", "job_events"})
    EXPECT_EQ(db.exec(std::string("SELECT count(*) FROM shop.") + t).i64(0, 0), 0) << t;
  // A hub newer than the program is refused, naming both versions.
  db.exec("INSERT INTO public.cncstream_shop_schema (version, note) VALUES (999, 'future')");
  try {
    migrate(db);
    FAIL() << "a newer hub was migrated";
  } catch (const ShopError& e) {
    EXPECT_NE(std::string(e.what()).find("999"), std::string::npos) << e.what();
  }
}

// A hub that ran a later migration but not an earlier one (two branches'
// migrations merged: 4 ran, 2 was added beside it) gets the one it lacks.
TEST(ShopSchema, AMigrationTheHubLacksBelowItsNewestStillRuns) {
  SHOP_REQUIRE_POSTGRES();
  shoptest::TempPostgres pg;
  PgConnection db(pg.create_database("gap"));
  const auto& all = migrations();
  const auto find = [&](int v) {
    for (const auto& m : all)
      if (m.version == v) return m.sql;
    throw std::runtime_error("no migration " + std::to_string(v));
  };
  db.exec("CREATE TABLE public.cncstream_shop_schema (version integer PRIMARY KEY, note text NOT NULL,"
          " applied_at timestamptz NOT NULL DEFAULT now())");
  for (int v : {1, 4}) {
    db.exec(find(v));
    db.exec("INSERT INTO public.cncstream_shop_schema (version, note) VALUES ($1, 'by hand')", {std::to_string(v)});
  }
  EXPECT_EQ(db.exec("SELECT to_regprocedure('shop.view_machines()') IS NULL").text(0, 0), "t");
  const auto r = migrate(db);
  EXPECT_EQ(r.to, schema_version_known());
  EXPECT_EQ(db.exec("SELECT to_regprocedure('shop.view_machines()') IS NOT NULL").text(0, 0), "t")
      << "migration 2 did not run";
  EXPECT_EQ(db.exec("SELECT count(*) FROM public.cncstream_shop_schema").i64(0, 0),
            static_cast<std::int64_t>(all.size()));
}

// A PC's login calls its three functions and the shop view's read-only ones;
// nothing else.
TEST(ShopSecurity, APcRoleWorksOnlyThroughItsFunctions) {
  SHOP_REQUIRE_POSTGRES();
  shoptest::TempPostgres pg;
  const std::string admin_url = pg.create_database("sec");
  PgConnection admin(admin_url);
  migrate(admin);
  admin.exec("CREATE ROLE pc_a LOGIN IN ROLE cncstream_pc");
  admin.exec("CREATE ROLE office LOGIN IN ROLE cncstream_operator");
  PgConnection office(pg.url("sec", "office"));
  PgConnection pc(pg.url("sec", "pc_a"));
  Hub pc_hub(pc), office_hub(office);
  // Its functions work.
  pc_hub.heartbeat(machine("router1"), MachineState{}, 30);
  const auto id = office_hub.submit_job(gcode_job("a.nc"));
  const auto claimed = pc_hub.claim_job("router1", 30);
  ASSERT_TRUE(claimed);
  EXPECT_EQ(claimed->id, id);
  EXPECT_EQ(claimed->content, "G21\nG90\nG0 X1\n");
  EXPECT_EQ(pc_hub.report_events("router1", {{1, "2026-01-01T00:00:00Z", "job", id, R"({"state":"ready"})"}}), 1);
  // The shop view's reads, which never return a job's file.
  const auto view = pc.exec("SELECT shop.view_jobs(NULL, NULL, 10, NULL)").text(0, 0);
  EXPECT_NE(view.find("\"a.nc\""), std::string::npos) << view;
  EXPECT_EQ(view.find("content"), std::string::npos) << view;
  EXPECT_NE(pc.exec("SELECT shop.view_machines()").text(0, 0).find("router1"), std::string::npos);
  const auto changes = pc.exec("SELECT shop.view_changes('{router1}', $1::bigint[])", {"{" + std::to_string(id) + "}"}).text(0, 0);
  EXPECT_NE(changes.find("\"router1\""), std::string::npos) << changes;
  EXPECT_NE(changes.find("\"a.nc\""), std::string::npos) << changes;
  EXPECT_EQ(changes.find("content"), std::string::npos) << changes;
  EXPECT_NE(pc.exec("SELECT shop.view_job_events($1, 10)", {std::to_string(id)}).text(0, 0).find("\"ready\""), std::string::npos);
  // Nothing else: no table read or written, no other function.
  const std::vector<std::string> refused = {
      "SELECT * FROM shop.jobs",
      "SELECT * FROM shop.job_events",
      "SELECT * FROM shop.machines",
      "UPDATE shop.jobs SET status = 'pending'",
      "DELETE FROM shop.job_events",
      "INSERT INTO shop.job_events (machine_id, seq, at, kind) VALUES (1, 99, now(), 'x')",
      "SELECT shop.submit_job('x', 'gcode', '\\x00', NULL, '{}', NULL)",
      "SELECT shop.requeue_job(1, false)",
      "SELECT shop.expire_leases()",
      "SELECT shop.apply_event(1, 1, 'job', '{\"state\":\"done\"}')",
      "SELECT shop.job_json(NULL::shop.jobs)",
      "SELECT shop.machine_json(NULL::shop.machines)",
      "CREATE TABLE shop.mine (x int)",
  };
  for (const auto& sql : refused) {
    try {
      pc.exec(sql);
      ADD_FAILURE() << "the PC's role was allowed: " << sql;
    } catch (const ShopError& e) {
      EXPECT_EQ(pc.last_sqlstate(), "42501") << sql << ": " << e.what();  // insufficient_privilege
    }
  }
  // The operator submits and reads, but cannot claim or report as a PC.
  EXPECT_GE(office.exec("SELECT count(*) FROM shop.jobs").i64(0, 0), 1);
  EXPECT_THROW(office.exec("SELECT * FROM shop.claim_job('router1', 30)"), ShopError);
  EXPECT_THROW(office.exec("UPDATE shop.jobs SET status = 'pending'"), ShopError);
  // The job is where the PC's event put it.
  EXPECT_EQ(admin.exec("SELECT status FROM shop.jobs WHERE id = $1", {std::to_string(id)}).text(0, 0), "awaiting_operator");
}

// Four PCs (one connection each) with two machines each claim from one queue
// of 200 jobs at once: every job is claimed exactly once, by a machine that
// can do it, and each claimed job waits for its operator.
TEST(ShopClaim, FourPcsWithTwoMachinesEachClaimTwoHundredJobsEachOnce) {
  SHOP_REQUIRE_POSTGRES();
  shoptest::TempPostgres pg;
  const std::string url = pg.create_database("claims");
  PgConnection admin(url);
  migrate(admin);
  Hub admin_hub(admin);
  // Machines: m0..m7; the odd ones hold the 4th axis, m5 alone takes "big" parts.
  std::map<std::string, std::set<std::string>> caps;
  for (int i = 0; i < 8; ++i) {
    std::vector<std::string> c;
    if (i % 2) c.push_back("4th-axis");
    if (i == 5) c.push_back("big");
    const std::string name = "m" + std::to_string(i);
    caps[name] = {c.begin(), c.end()};
    admin_hub.heartbeat(machine(name, c), MachineState{}, 60);
  }
  std::map<std::int64_t, Submission> submitted;
  for (int i = 0; i < 200; ++i) {
    Submission s = i % 10 == 3 ? gcode_job("axis.nc", {"4th-axis"})
                   : i % 25 == 7 ? gcode_job("big.nc", {"big"})
                   : i % 20 == 11 ? gcode_job("only-m2.nc", {}, "m2")
                                  : gcode_job("plain.nc");
    submitted[admin_hub.submit_job(s)] = s;
  }
  std::mutex mu;
  std::vector<std::pair<std::int64_t, std::string>> claims;
  std::atomic<int> errors{0};
  std::vector<std::thread> pcs;
  for (int pc = 0; pc < 4; ++pc)
    pcs.emplace_back([&, pc] {
      try {
        PgConnection db(url);
        Hub hub(db);
        const std::string a = "m" + std::to_string(2 * pc), b = "m" + std::to_string(2 * pc + 1);
        bool more_a = true, more_b = true;
        while (more_a || more_b) {
          for (auto [name, more] : {std::pair<const std::string&, bool*>{a, &more_a}, {b, &more_b}}) {
            if (!*more) continue;
            const auto j = hub.claim_job(name, 60);
            if (!j) {
              *more = false;
              continue;
            }
            std::lock_guard lock(mu);
            claims.emplace_back(j->id, name);
          }
        }
      } catch (const std::exception& e) {
        ADD_FAILURE() << e.what();
        ++errors;
      }
    });
  for (auto& t : pcs) t.join();
  ASSERT_EQ(errors, 0);
  std::map<std::int64_t, int> times;
  for (const auto& [id, name] : claims) {
    ++times[id];
    const auto& s = submitted.at(id);
    for (const auto& need : s.needs) EXPECT_TRUE(caps[name].count(need)) << "job " << id << " needs " << need << ", " << name;
    if (!s.machine.empty()) {
      EXPECT_EQ(name, s.machine) << "job " << id;
    }
  }
  EXPECT_EQ(claims.size(), 200u);
  EXPECT_EQ(times.size(), 200u);
  for (const auto& [id, n] : times) EXPECT_EQ(n, 1) << "job " << id << " claimed " << n << " times";
  EXPECT_EQ(admin.exec("SELECT count(*) FROM shop.jobs WHERE status = 'assigned'").i64(0, 0), 200);
  // Claimed is not started: the operator starts it.
  EXPECT_EQ(admin.exec("SELECT count(*) FROM shop.jobs WHERE started_at IS NOT NULL").i64(0, 0), 0);
}

// Replayed events are stored once; a lapsed lease interrupts the job with
// its last reported line and nothing claims it again by itself.
TEST(ShopLease, ALapsedLeaseInterruptsTheJobWithItsLastLineAndNobodyTakesIt) {
  SHOP_REQUIRE_POSTGRES();
  shoptest::TempPostgres pg;
  const std::string url = pg.create_database("lease");
  PgConnection db(url);
  migrate(db);
  Hub hub(db);
  hub.heartbeat(machine("r1"), MachineState{}, 30);
  hub.heartbeat(machine("r2"), MachineState{}, 30);
  const auto id = hub.submit_job(gcode_job("part.nc"));
  ASSERT_TRUE(hub.claim_job("r1", 0.5));
  const std::vector<OutboxEvent> events = {
      {1, "2026-01-01T00:00:00Z", "job", id, R"({"state":"ready"})"},
      {2, "2026-01-01T00:00:01Z", "job", id, R"({"state":"running","last_line":0})"},
      {3, "2026-01-01T00:00:02Z", "progress", id, R"({"line":17})"},
  };
  EXPECT_EQ(hub.report_events("r1", events), 3);
  EXPECT_EQ(hub.report_events("r1", events), 3);  // a replay
  EXPECT_EQ(db.exec("SELECT count(*), count(DISTINCT seq) FROM shop.job_events").i64(0, 0), 3);
  EXPECT_EQ(db.exec("SELECT status FROM shop.jobs WHERE id = $1", {std::to_string(id)}).text(0, 0), "running");
  // r1's PC goes quiet; r2's heartbeat sweeps the lapsed lease.
  std::this_thread::sleep_for(std::chrono::milliseconds(700));
  hub.heartbeat(machine("r2"), MachineState{}, 30);
  const auto r = db.exec("SELECT status, last_line, message FROM shop.jobs WHERE id = $1", {std::to_string(id)});
  EXPECT_EQ(r.text(0, 0), "interrupted");
  EXPECT_EQ(r.i64(0, 1), 17);
  EXPECT_NE(r.text(0, 2).find("last reported line 17"), std::string::npos) << r.text(0, 2);
  EXPECT_FALSE(hub.claim_job("r2", 30)) << "an interrupted job was handed to another machine";
  // Its PC comes back and reports the truth: it completed there.
  EXPECT_EQ(hub.report_events("r1", {{4, "2026-01-01T00:00:09Z", "job", id, R"({"state":"done","last_line":40})"}}), 4);
  EXPECT_EQ(db.exec("SELECT status FROM shop.jobs WHERE id = $1", {std::to_string(id)}).text(0, 0), "completed");
  // An operator's requeue (same machine) is the only way back into the queue.
  const auto id2 = hub.submit_job(gcode_job("part2.nc"));
  ASSERT_TRUE(hub.claim_job("r1", 0.2));
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  hub.heartbeat(machine("r2"), MachineState{}, 30);
  EXPECT_EQ(db.exec("SELECT status FROM shop.jobs WHERE id = $1", {std::to_string(id2)}).text(0, 0), "interrupted");
  hub.requeue_job(id2, true);
  EXPECT_FALSE(hub.claim_job("r2", 30)) << "a job requeued for r1 went to r2";
  const auto again = hub.claim_job("r1", 30);
  ASSERT_TRUE(again);
  EXPECT_EQ(again->id, id2);
  EXPECT_EQ(again->resume_after_line, 0) << "no line was reported: the same machine starts from the top";
}

// Migration 5: requeued on the machine it ran on, a job carries its last
// reported line to resume after, and only that machine claims it; requeued
// anywhere, it is a restart from the top that any machine that can claims.
TEST(ShopLease, RequeuedOnTheSameMachineItResumesAfterItsLastLineThereAnywhereItRestarts) {
  SHOP_REQUIRE_POSTGRES();
  shoptest::TempPostgres pg;
  PgConnection db(pg.create_database("resume"));
  migrate(db);
  Hub hub(db);
  hub.heartbeat(machine("r1"), MachineState{}, 30);
  hub.heartbeat(machine("r2"), MachineState{}, 30);
  const auto id = hub.submit_job(gcode_job("part.nc"));
  EXPECT_THROW(hub.requeue_job(id, true), ShopError) << "a pending job is not requeued";
  ASSERT_TRUE(hub.claim_job("r1", 0.3));
  hub.report_events("r1", {{1, "2026-01-01T00:00:00Z", "job", id, R"({"state":"running","last_line":0})"},
                           {2, "2026-01-01T00:00:01Z", "progress", id, R"({"line":23})"}});
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  hub.heartbeat(machine("r2"), MachineState{}, 30);  // sweeps r1's lapsed lease
  const auto row = [&] {
    return db.exec("SELECT j.status, j.last_line, j.resume_after_line, m.name, j.message, j.machine FROM shop.jobs j"
                   " LEFT JOIN shop.machines m ON m.id = j.resume_machine_id WHERE j.id = $1",
                   {std::to_string(id)});
  };
  ASSERT_EQ(row().text(0, 0), "interrupted");
  hub.requeue_job(id, true);
  EXPECT_EQ(row().text(0, 0), "pending");
  EXPECT_EQ(row().i64(0, 2), 23) << "the line to resume after is the last one reported";
  EXPECT_EQ(row().text(0, 3), "r1");
  EXPECT_TRUE(row().is_null(0, 5)) << "the submitter's own choice of machine (any) is kept";
  EXPECT_NE(row().text(0, 4).find("to resume after line 23"), std::string::npos) << row().text(0, 4);
  EXPECT_FALSE(hub.claim_job("r2", 30)) << "a resume went to another machine";
  const auto resumed = hub.claim_job("r1", 0.3);
  ASSERT_TRUE(resumed);
  EXPECT_EQ(resumed->id, id);
  EXPECT_EQ(resumed->resume_after_line, 23);
  // Interrupted again, now requeued anywhere: from the top, for any machine.
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  hub.heartbeat(machine("r2"), MachineState{}, 30);
  ASSERT_EQ(row().text(0, 0), "interrupted");
  hub.requeue_job(id, false);
  EXPECT_TRUE(row().is_null(0, 2));
  EXPECT_EQ(row().i64(0, 1), 0);
  EXPECT_TRUE(row().is_null(0, 3)) << "a restart anywhere is for any machine that can";
  EXPECT_TRUE(row().is_null(0, 5));
  const auto restarted = hub.claim_job("r2", 30);
  ASSERT_TRUE(restarted);
  EXPECT_EQ(restarted->id, id);
  EXPECT_EQ(restarted->resume_after_line, 0);
  // A job that never reached a machine cannot go back to "its" machine.
  const auto never = hub.submit_job(gcode_job("never.nc"));
  hub.cancel_job(never);
  try {
    hub.requeue_job(never, true);
    ADD_FAILURE() << "a job that never reached a machine was requeued on one";
  } catch (const ShopError& e) {
    EXPECT_NE(std::string(e.what()).find("never reached a machine"), std::string::npos) << e.what();
  }
}
