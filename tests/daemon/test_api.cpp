// The API against a daemon on a loopback port with simulated machines:
// upload, jobs to done with the simulator's cut verified, hold / resume /
// stop, the queue, a restart mid-job, a vanishing port, the jog dead man,
// and the OpenAPI document against the router's table.
#include <gtest/gtest.h>

#include <set>

#include "cncstream/daemon/api.hpp"
#include "cncstream/daemon/job_manager.hpp"
#include "cncstream/session/simulator_port.hpp"
#include "cncstream/transport/journal.hpp"
#include "daemon_test_util.hpp"

using namespace dtest;
using cncstream::daemon::DaemonConfig;

namespace {

const std::string kClient = "tester-1";

std::string plaque() { return std::string(CNCSTREAM_SOURCE_DIR) + "/examples/plaque.stl"; }

json upload(const Http& h, const std::string& bytes, const std::string& name) {
  const auto r = h.request("POST", "/api/v1/files?name=" + name, bytes, {{"Content-Type", "application/octet-stream"}});
  EXPECT_TRUE(r.status == 201 || r.status == 200) << r.status << " " << r.body;
  return r.status == 201 || r.status == 200 ? r.j() : json();
}

// A program of `n` slow moves back and forth along X (each `mm` long at F`feed`).
std::string slow_program(int n, double mm, double feed) {
  std::string g = "G21\nG90\nG0 Z5\n";
  for (int i = 0; i < n; ++i) {
    char b[64];
    std::snprintf(b, sizeof b, "G1 X%.3f Y0 F%.0f\n", (i % 2) ? 0.0 : mm, feed);
    g += b;
  }
  return g;
}

bool machines_ready(const Http& h) {
  const auto r = h.get("/api/v1/machines");
  if (r.status != 200) return false;
  const json list = r.j();  // kept: a range-for over a temporary's member dangles
  for (const auto& m : list["machines"])
    if (m["link"] != "ready") return false;
  return true;
}

json job(const Http& h, std::int64_t id) { return h.get("/api/v1/jobs/" + std::to_string(id)).j(); }

bool wait_state(const Http& h, std::int64_t id, const std::string& state, double timeout_s) {
  return wait_for([&] { return job(h, id)["state"] == state; }, timeout_s);
}

Http with_client(Http h, const std::string& id = kClient) {
  h.headers["X-Client-Id"] = id;
  return h;
}

}  // namespace

TEST(DaemonApi, PlaqueOnTwoSimulatorsAtOnceRunsToDoneWithProgressAndNoGouge) {
  const auto dir = temp_dir("e2e");
  auto cfg = test_config(dir);
  for (auto& m : cfg.machines) m.sim_resolution = 0.2;
  RunningDaemon d(cfg);
  const Http h = with_client(d.http);
  ASSERT_TRUE(wait_for([&] { return machines_ready(h); }, 30));

  const auto f = upload(h, read_file(plaque()), "plaque.stl");
  EXPECT_EQ(f["kind"], "stl");
  EXPECT_EQ(f["facets"], 34908);
  EXPECT_EQ(f["id"].get<std::string>().size(), 64u);

  WsClient ws;
  ASSERT_EQ(ws.connect(d.port(), "/api/v1/ws?client_id=" + kClient), 101);
  ASSERT_TRUE(ws.wait_message([](const json& j) { return j["type"] == "hello"; }, 5));
  ws.send(json{{"type", "subscribe"}, {"machines", {"*"}}, {"id", 1}});
  ASSERT_TRUE(ws.wait_message([](const json& j) { return j["type"] == "ack" && j["id"] == 1; }, 5));

  // Finishing alone: the test is about two machines at once, not the CAM.
  const json params = {{"tool", "ball:3.175"}, {"stepover", 3}, {"stock", "none"}, {"strategy", "raster"}};
  std::vector<std::int64_t> ids;
  for (const char* m : {"sim1", "sim2"}) {
    ASSERT_EQ(h.post(std::string("/api/v1/machines/") + m + "/control").status, 200);
    const auto r = h.post("/api/v1/jobs", {{"machine", m}, {"file", f["id"]}, {"params", params}});
    ASSERT_EQ(r.status, 201) << r.body;
    ids.push_back(r.j()["id"].get<std::int64_t>());
  }
  for (auto id : ids) ASSERT_TRUE(wait_state(h, id, "ready", 60)) << job(h, id).dump();
  // The same parameters again: served from the cache at once.
  {
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = h.post("/api/v1/jobs", {{"machine", "sim1"}, {"file", f["id"]}, {"params", params}});
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    ASSERT_EQ(r.status, 201);
    EXPECT_EQ(r.j()["state"], "ready");
    EXPECT_EQ(r.j()["generation"]["cached"], true);
    EXPECT_LT(ms, 1000);  // generous for a loaded test machine; the benchmark measures the real figure
    ASSERT_EQ(h.post("/api/v1/jobs/" + std::to_string(r.j()["id"].get<std::int64_t>()) + "/cancel").status, 200);
  }
  for (auto id : ids) {
    const auto r = h.post("/api/v1/jobs/" + std::to_string(id) + "/start");
    ASSERT_EQ(r.status, 202) << r.body;
  }
  std::set<std::int64_t> done;
  bool saw_progress = false;
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(180);
  while (done.size() < ids.size() && std::chrono::steady_clock::now() < end) {
    const auto m = ws.wait_message([](const json& j) { return j["type"] == "job"; }, 60);
    ASSERT_TRUE(m) << "no job message";
    if ((*m)["progress"]["lines_answered"].get<long>() > 0 && (*m)["state"] == "running") saw_progress = true;
    if ((*m)["state"] == "done") done.insert((*m)["job"].get<std::int64_t>());
    ASSERT_NE((*m)["state"], "failed") << m->dump();
  }
  EXPECT_EQ(done.size(), 2u);
  EXPECT_TRUE(saw_progress);
  for (auto id : ids) {
    ASSERT_TRUE(wait_for([&] { return !job(h, id)["verify"].is_null(); }, 120)) << job(h, id).dump();
    const auto j = job(h, id);
    EXPECT_EQ(j["verify"]["gouged"], false) << j["verify"]["text"];
    EXPECT_EQ(j["progress"]["eta_s"], 0.0);
    // The run is in the CLI's journal (cncstream jobs lists it).
    cncstream::transport::Journal journal(cfg.journal);
    const auto rec = journal.job(j["journal_id"].get<std::int64_t>());
    ASSERT_TRUE(rec);
    EXPECT_EQ(rec->outcome.value_or(""), "completed");
  }
  // The machines reconnected to fresh simulators after their verify.
  EXPECT_TRUE(wait_for([&] { return machines_ready(h); }, 30));
  d.shutdown();
  std::filesystem::remove_all(dir);
}

TEST(DaemonApi, HoldResumeAndStopARunningJob) {
  const auto dir = temp_dir("hold");
  auto cfg = test_config(dir);
  cfg.machines = {sim_machine("sim1", "1")};  // real time: the job lasts long enough to hold it
  RunningDaemon d(cfg);
  const Http h = with_client(d.http);
  ASSERT_TRUE(wait_for([&] { return machines_ready(h); }, 30));
  const auto f = upload(h, slow_program(60, 10, 600), "slow.nc");
  EXPECT_EQ(f["kind"], "gcode");
  auto r = h.post("/api/v1/jobs", {{"machine", "sim1"}, {"file", f["id"]}});
  ASSERT_EQ(r.status, 201) << r.body;
  const auto id = r.j()["id"].get<std::int64_t>();
  const std::string base = "/api/v1/jobs/" + std::to_string(id);
  ASSERT_TRUE(wait_state(h, id, "ready", 30));
  // Nothing moves without control (fail closed).
  EXPECT_EQ(h.post("/api/v1/machines/sim1/jog", {{"dir", {1, 0, 0}}, {"distance", 1}, {"feed", 100}}).status, 409);
  EXPECT_EQ(h.post(base + "/start").status, 409);
  EXPECT_EQ(d.http.post(base + "/start").status, 428);  // no client id at all
  ASSERT_EQ(h.post("/api/v1/machines/sim1/control").status, 200);
  ASSERT_EQ(h.post(base + "/start").status, 202);
  ASSERT_TRUE(wait_for([&] { return job(h, id)["progress"]["lines_answered"].get<long>() >= 4; }, 30));
  // Hold is accepted from anyone authenticated (another client, no control).
  ASSERT_EQ(with_client(d.http, "other").post(base + "/hold").status, 202);
  ASSERT_TRUE(wait_state(h, id, "held", 10)) << job(h, id).dump();
  // Resume needs control.
  EXPECT_EQ(with_client(d.http, "other").post(base + "/resume").status, 409);
  // The console is refused during a job.
  EXPECT_EQ(h.post("/api/v1/machines/sim1/console", {{"line", "$$"}}).status, 409);
  ASSERT_EQ(h.post(base + "/resume").status, 202);
  ASSERT_TRUE(wait_state(h, id, "running", 10));
  ASSERT_EQ(with_client(d.http, "other").post(base + "/stop").status, 202);
  ASSERT_TRUE(wait_state(h, id, "stopped", 30)) << job(h, id).dump();
  const auto j = job(h, id);
  EXPECT_GT(j["progress"]["last_answered_line"].get<long>(), 0);
  EXPECT_LT(j["progress"]["last_answered_line"].get<long>(), 63);
  // A resume plan for the stopped job is shown, and becomes a job only when confirmed.
  r = h.post(base + "/resume-plan", {{"from_line", 10}});
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(r.j()["from_line"], 10);
  EXPECT_FALSE(r.j()["preamble"].empty());
  const auto confirmed = h.post(base + "/resume-confirm", {{"plan_id", r.j()["plan_id"]}});
  ASSERT_EQ(confirmed.status, 201) << confirmed.body;
  EXPECT_EQ(confirmed.j()["state"], "ready");  // still needs an explicit start
  EXPECT_EQ(confirmed.j()["resumed_from"], id);
  EXPECT_EQ(h.post(base + "/resume-confirm", {{"plan_id", r.j()["plan_id"]}}).status, 404);  // one use
  d.shutdown();
  std::filesystem::remove_all(dir);
}

// A tool change's M0 holds the machine while the job runs on: the job says
// so, and its resume is the cycle start that goes on.
TEST(DaemonApi, ResumeGoesOnAfterTheProgramsToolChangePause) {
  const auto dir = temp_dir("pause");
  auto cfg = test_config(dir);
  cfg.machines = {sim_machine("sim1")};
  RunningDaemon d(cfg);
  const Http h = with_client(d.http);
  ASSERT_TRUE(wait_for([&] { return machines_ready(h); }, 30));
  const auto f = upload(h,
                        "G21 G90\nG0 Z5\nG1 X10 F1000\n(TOOL CHANGE: mount T2)\nM0\nG1 X0 F1000\nG1 Y5\nM2\n",
                        "pause.nc");
  auto r = h.post("/api/v1/jobs", {{"machine", "sim1"}, {"file", f["id"]}});
  ASSERT_EQ(r.status, 201) << r.body;
  const auto id = r.j()["id"].get<std::int64_t>();
  const std::string base = "/api/v1/jobs/" + std::to_string(id);
  ASSERT_TRUE(wait_state(h, id, "ready", 30));
  ASSERT_EQ(h.post("/api/v1/machines/sim1/control").status, 200);
  ASSERT_EQ(h.post(base + "/start").status, 202);
  ASSERT_TRUE(wait_for([&] { return job(h, id)["message"].get<std::string>().starts_with("paused at line 5"); }, 30))
      << job(h, id).dump();
  EXPECT_EQ(job(h, id)["state"], "running");
  EXPECT_EQ(with_client(d.http, "other").post(base + "/resume").status, 409);  // control is still needed
  ASSERT_EQ(h.post(base + "/resume").status, 202) << h.post(base + "/resume").body;
  ASSERT_TRUE(wait_state(h, id, "done", 30)) << job(h, id).dump();
  EXPECT_EQ(job(h, id)["progress"]["last_answered_line"], 8);
  EXPECT_EQ(job(h, id)["message"].get<std::string>().find("paused"), std::string::npos) << job(h, id).dump();
  d.shutdown();
  std::filesystem::remove_all(dir);
}

TEST(DaemonApi, QueueKeepsItsOrderAndNothingStartsByItself) {
  const auto dir = temp_dir("queue");
  RunningDaemon d(test_config(dir));
  const Http h = with_client(d.http);
  ASSERT_TRUE(wait_for([&] { return machines_ready(h); }, 30));
  const auto f = upload(h, slow_program(5, 1, 1000), "short.nc");
  std::vector<std::int64_t> ids;
  for (int i = 0; i < 3; ++i) {
    const auto r = h.post("/api/v1/jobs", {{"machine", "sim2"}, {"file", f["id"]}});
    ASSERT_EQ(r.status, 201);
    ids.push_back(r.j()["id"].get<std::int64_t>());
  }
  for (auto id : ids) ASSERT_TRUE(wait_state(h, id, "ready", 30));
  auto order = [&] {
    std::vector<std::int64_t> o;
    const json list = h.get("/api/v1/jobs?machine=sim2").j();
    for (const auto& j : list["jobs"])
      if (j["state"] == "ready") o.push_back(j["id"].get<std::int64_t>());
    return o;
  };
  EXPECT_EQ(order(), ids);
  ASSERT_EQ(h.post("/api/v1/jobs/" + std::to_string(ids[2]) + "/move", {{"position", 0}}).status, 200);
  EXPECT_EQ(order(), (std::vector<std::int64_t>{ids[2], ids[0], ids[1]}));
  ASSERT_EQ(h.post("/api/v1/machines/sim2/control").status, 200);
  ASSERT_EQ(h.post("/api/v1/jobs/" + std::to_string(ids[0]) + "/cancel").status, 200);
  EXPECT_EQ(order(), (std::vector<std::int64_t>{ids[2], ids[1]}));
  EXPECT_EQ(job(h, ids[0])["state"], "cancelled");
  EXPECT_EQ(h.post("/api/v1/jobs/" + std::to_string(ids[0]) + "/start").status, 409);
  EXPECT_FALSE(h.get("/api/v1/machines/sim2").j()["job_active"].get<bool>());
  ASSERT_EQ(h.post("/api/v1/jobs/" + std::to_string(ids[1]) + "/start").status, 202);
  ASSERT_TRUE(wait_state(h, ids[1], "done", 30));
  EXPECT_EQ(job(h, ids[2])["state"], "ready");
  // A file in use by an unfinished job is not deleted.
  EXPECT_EQ(h.del("/api/v1/files/" + f["id"].get<std::string>()).status, 409);
  d.shutdown();
  std::filesystem::remove_all(dir);
}

TEST(DaemonApi, RestartMidJobShowsItInterruptedAndStartsNothing) {
  const auto dir = temp_dir("restart");
  auto cfg = test_config(dir);
  cfg.machines = {sim_machine("sim1", "1")};
  std::int64_t running = 0, waiting = 0;
  long answered = 0;
  {
    RunningDaemon d(cfg);
    const Http h = with_client(d.http);
    ASSERT_TRUE(wait_for([&] { return machines_ready(h); }, 30));
    const auto f = upload(h, slow_program(60, 10, 600), "slow.nc");
    running = h.post("/api/v1/jobs", {{"machine", "sim1"}, {"file", f["id"]}}).j()["id"].get<std::int64_t>();
    waiting = h.post("/api/v1/jobs", {{"machine", "sim1"}, {"file", f["id"]}}).j()["id"].get<std::int64_t>();
    ASSERT_TRUE(wait_state(h, running, "ready", 30));
    ASSERT_TRUE(wait_state(h, waiting, "ready", 30));
    ASSERT_EQ(h.post("/api/v1/machines/sim1/control").status, 200);
    ASSERT_EQ(h.post("/api/v1/jobs/" + std::to_string(running) + "/start").status, 202);
    ASSERT_TRUE(wait_for([&] { return job(h, running)["progress"]["lines_answered"].get<long>() >= 4; }, 30));
    // The journal records progress at most every 0.1 s: wait until a row
    // holds answered lines, as it would for a daemon killed a moment later.
    const auto journal_id = job(h, running)["journal_id"].get<std::int64_t>();
    cncstream::transport::Journal reader(cfg.journal);
    ASSERT_TRUE(wait_for([&] {
      const auto p = reader.last_progress(journal_id);
      answered = p ? static_cast<long>(p->last_line) : 0;
      return answered >= 4;
    }, 30));
    d.shutdown();  // the daemon goes away under the running job
  }
  RunningDaemon d2(cfg);
  const Http h = with_client(d2.http);
  const auto j = job(h, running);
  EXPECT_EQ(j["state"], "interrupted") << j.dump();
  EXPECT_GE(j["progress"]["last_answered_line"].get<long>(), answered);
  EXPECT_NE(j["message"].get<std::string>().find("not resumed"), std::string::npos);
  ASSERT_TRUE(wait_state(h, waiting, "ready", 30));  // regenerated, waiting for a start
  ASSERT_TRUE(wait_for([&] { return machines_ready(h); }, 30));
  EXPECT_FALSE(h.get("/api/v1/machines/sim1").j()["job_active"].get<bool>());
  EXPECT_EQ(job(h, waiting)["state"], "ready");
  cncstream::transport::Journal journal(cfg.journal);
  EXPECT_EQ(journal.job(j["journal_id"].get<std::int64_t>())->outcome.value_or(""), "interrupted");
  d2.shutdown();
  std::filesystem::remove_all(dir);
}

TEST(DaemonApi, VanishingSimulatorInterruptsTheJobAndReconnects) {
  const auto dir = temp_dir("vanish");
  auto cfg = test_config(dir);
  auto m = sim_machine("flaky");
  m.sim_vanish_after = 60;
  m.sim_verify = false;
  cfg.machines = {m};
  RunningDaemon d(cfg);
  const Http h = with_client(d.http);
  ASSERT_TRUE(wait_for([&] { return machines_ready(h); }, 30));
  WsClient ws;
  ASSERT_EQ(ws.connect(d.port(), "/api/v1/ws?client_id=" + kClient), 101);
  ws.send(json{{"type", "subscribe"}, {"machines", {"flaky"}}});
  const auto f = upload(h, slow_program(300, 5, 3000), "long.nc");
  const auto id = h.post("/api/v1/jobs", {{"machine", "flaky"}, {"file", f["id"]}}).j()["id"].get<std::int64_t>();
  ASSERT_TRUE(wait_state(h, id, "ready", 30));
  ASSERT_EQ(h.post("/api/v1/machines/flaky/control").status, 200);
  ASSERT_EQ(h.post("/api/v1/jobs/" + std::to_string(id) + "/start").status, 202);
  ASSERT_TRUE(ws.wait_message([](const json& j) { return j["type"] == "link" && j["link"] == "disconnected"; }, 60));
  ASSERT_TRUE(wait_state(h, id, "interrupted", 10)) << job(h, id).dump();
  EXPECT_NE(job(h, id)["message"].get<std::string>().find("went away"), std::string::npos);
  ASSERT_TRUE(ws.wait_message([](const json& j) { return j["type"] == "link" && j["link"] == "ready"; }, 30));
  EXPECT_FALSE(h.get("/api/v1/machines/flaky").j()["job_active"].get<bool>());  // never resumed by itself
  EXPECT_EQ(job(h, id)["state"], "interrupted");
  d.shutdown();
  std::filesystem::remove_all(dir);
}

TEST(DaemonApi, APortAbsentAtStartIsOpenedWhenItAppears) {
  const auto dir = temp_dir("absent");
  auto cfg = test_config(dir);
  cncstream::daemon::MachineConfig m;
  m.name = "late";
  m.port = (dir / "ttyLATE").string();  // a device path that does not exist yet
  m.reconnect_s = 0.2;
  cfg.machines = {m};
  RunningDaemon d(cfg);
  const Http h = with_client(d.http);
  EXPECT_NE(h.get("/api/v1/machines/late").j()["link"], "ready");
  // The controller appears (a simulator behind a symlink at that path).
  cncstream::session::SimulatorOptions so;
  so.link = dir / "ttyLATE";
  cncstream::session::SimulatorPort sim(so);
  sim.start();
  // Identification: no banner reaches a port opened after power-on, so it
  // asks ($I) after its banner time-out (3 s).
  EXPECT_TRUE(wait_for([&] { return h.get("/api/v1/machines/late").j()["link"] == "ready"; }, 20));
  d.shutdown();
  sim.finish(false);
  std::filesystem::remove_all(dir);
}

TEST(DaemonApi, ContinuousJogStopsWhenRenewalsStopOrTheSocketDrops) {
  const auto dir = temp_dir("jog");
  auto cfg = test_config(dir);
  cfg.machines = {sim_machine("sim1", "1")};
  RunningDaemon d(cfg);
  const Http h = with_client(d.http);
  ASSERT_TRUE(wait_for([&] { return machines_ready(h); }, 30));
  // jog_held: the continuous jog's lease is alive (the cancel is sent the moment it ends);
  // jogging: anything still moving.
  auto jogging = [&] { return h.get("/api/v1/machines/sim1").j()["jog_held"].get<bool>(); };
  auto moving = [&] { return h.get("/api/v1/machines/sim1").j()["jogging"].get<bool>(); };
  WsClient ws;
  ASSERT_EQ(ws.connect(d.port(), "/api/v1/ws?client_id=" + kClient), 101);
  const json start = {{"type", "jog_start"}, {"machine", "sim1"}, {"dir", {1, 0, 0}}, {"feed", 1000}, {"id", 7}};
  ws.send(start);
  const auto refused = ws.wait_message([](const json& j) { return j["type"] == "error" || j["type"] == "ack"; }, 5);
  ASSERT_TRUE(refused);
  EXPECT_EQ((*refused)["type"], "error");  // no control: no motion
  EXPECT_EQ((*refused)["code"], "control_required");
  ASSERT_EQ(h.post("/api/v1/machines/sim1/control").status, 200);
  ws.send(start);
  const auto ok = ws.wait_message([](const json& j) { return j["type"] == "error" || j["type"] == "ack"; }, 5);
  ASSERT_TRUE(ok);
  ASSERT_EQ((*ok)["type"], "ack") << ok->dump();
  ASSERT_TRUE(jogging());
  // Renewals keep it alive...
  for (int i = 0; i < 5; ++i) {
    ws.send(json{{"type", "jog_renew"}, {"machine", "sim1"}});
    std::this_thread::sleep_for(std::chrono::milliseconds(150));
  }
  EXPECT_TRUE(jogging());
  // ...silence ends it: the 0.3 s lease runs out.
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_TRUE(wait_for([&] { return !jogging(); }, 2));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 0.6);
  // A dropped socket ends the jog at once, and its control.
  ASSERT_TRUE(wait_for([&] { return !moving(); }, 10));
  ws.send(start);
  ASSERT_TRUE(ws.wait_message([](const json& j) { return j["type"] == "ack"; }, 5));
  ASSERT_TRUE(jogging());
  ws.send(json{{"type", "jog_renew"}, {"machine", "sim1"}});
  ws.close();
  const auto t1 = std::chrono::steady_clock::now();
  ASSERT_TRUE(wait_for([&] { return !jogging(); }, 2));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count(), 0.25);
  EXPECT_TRUE(wait_for([&] { return h.get("/api/v1/machines/sim1/control").j()["holder"].is_null(); }, 2));
  d.shutdown();
  std::filesystem::remove_all(dir);
}

TEST(DaemonApi, OpenApiDocumentDescribesExactlyTheRoutes) {
  const auto dir = temp_dir("openapi");
  RunningDaemon d(test_config(dir));
  const auto r = d.http.get("/api/v1/openapi.json");
  ASSERT_EQ(r.status, 200);
  const json doc = r.j();
  std::set<std::string> documented, served;
  for (const auto& [path, ops] : doc["paths"].items())
    for (const auto& [method, op] : ops.items()) {
      std::string m = method;
      for (auto& c : m) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
      // Path templates: OpenAPI names each placeholder; the router's
      // "/static/*" is OpenAPI's "/static/{path}".
      std::string p = path;
      if (p == "/static/{path}") p = "/static/*";
      documented.insert(m + " " + p);
    }
  for (const auto& route : d.daemon().api().router().routes()) {
    std::string p = route.pattern;
    // The router's placeholder names may differ; compare shapes.
    served.insert(route.method + " " + p);
  }
  auto shape = [](std::set<std::string> s) {
    std::set<std::string> out;
    for (auto x : s) {
      std::string y;
      bool in = false;
      for (char c : x) {
        if (c == '{') {
          in = true;
          y += "{}";
        } else if (c == '}') {
          in = false;
        } else if (!in) {
          y += c;
        }
      }
      out.insert(y);
    }
    return out;
  };
  EXPECT_EQ(shape(documented), shape(served));
  d.shutdown();
  std::filesystem::remove_all(dir);
}

// A pendant configured for a machine: the daemon starts, serves, and looks
// for the receiver without one plugged in (hotplug or polling), and stops
// cleanly with its reader thread.
TEST(DaemonApi, StartsWithAPendantForAMachineAndNoReceiverPluggedIn) {
  const auto dir = temp_dir("pendant");
  auto cfg = test_config(dir);
  cncstream::daemon::PendantSection p;
  p.machine = cfg.machines.front().name;
  cfg.pendants.push_back(p);
  RunningDaemon d(cfg);
  EXPECT_EQ(d.daemon().pendant_count(), 1u);
  const Http h = with_client(d.http);
  ASSERT_TRUE(wait_for([&] { return machines_ready(h); }, 30));
  d.shutdown();
}

// Each machine's programs are fitted to its own link: the same part and
// parameters for a 115,200-baud machine and a 9,600-baud one are two
// programs; on the slow wire F is lowered where the moves cannot arrive in
// time, the operations say what the wire allows, and the estimate is longer.
TEST(DaemonApi, EachMachinesProgramIsFittedToItsOwnLink) {
  const auto dir = temp_dir("link");
  auto cfg = test_config(dir);
  cfg.machines[1].baud = 9600;
  RunningDaemon d(cfg);
  const Http h = with_client(d.http);
  ASSERT_TRUE(wait_for([&] { return machines_ready(h); }, 30));
  const auto f = upload(h, read_file(plaque()), "plaque.stl");
  const json params = {{"tool", "ball:3.175"}, {"stepover", 3}, {"stock", "none"}, {"strategy", "raster"}, {"feed", 3000}};
  std::vector<std::int64_t> ids;
  for (const char* m : {"sim1", "sim2"}) {
    const auto r = h.post("/api/v1/jobs", {{"machine", m}, {"file", f["id"]}, {"params", params}});
    ASSERT_EQ(r.status, 201) << r.body;
    ids.push_back(r.j()["id"].get<std::int64_t>());
  }
  for (auto id : ids) ASSERT_TRUE(wait_state(h, id, "ready", 60)) << job(h, id).dump();
  for (auto id : ids)
    ASSERT_TRUE(wait_for([&] { return !job(h, id)["program"]["estimated_s"].is_null(); }, 60)) << job(h, id).dump();
  const json fast = job(h, ids[0]), slow = job(h, ids[1]);
  EXPECT_EQ(slow["generation"]["cached"], false) << "another link is another program";
  const json& fop = fast["program"]["operations"][0];
  const json& sop = slow["program"]["operations"][0];
  ASSERT_TRUE(fop["share_below_feed"].is_number() && sop["share_below_feed"].is_number()) << fop.dump() << sop.dump();
  EXPECT_EQ(fop["share_below_feed"].get<double>(), 0.0) << fop.dump();
  EXPECT_GT(sop["share_below_feed"].get<double>(), 0.0) << sop.dump();
  ASSERT_TRUE(sop["wire_feed"].is_number()) << sop.dump();
  EXPECT_LT(sop["wire_feed"].get<double>(), 3000.0) << "F3000 cannot arrive over 9,600 baud everywhere";
  if (fop["wire_feed"].is_number()) {
    EXPECT_GT(fop["wire_feed"].get<double>(), 9 * sop["wire_feed"].get<double>());  // twelve times the bytes a second
  }
  EXPECT_GT(slow["program"]["estimated_s"].get<double>(), fast["program"]["estimated_s"].get<double>());
  d.shutdown();
  std::filesystem::remove_all(dir);
}
