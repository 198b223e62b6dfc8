// Tool changes of daemon jobs against the simulator (docs/tool-change.md):
// the session's routine runs at the program's change with the machine's
// [machine.tool_change] settings or the job's own; the prompt is in the
// machine's state and on the WebSocket; jogs are refused while the job
// streams and accepted at the prompt; confirm goes on and the job ends done
// with the measured offset in the journal; decline and a probe that never
// triggers end the job with the length unknown.
#include <gtest/gtest.h>

#include "cncstream/transport/journal.hpp"
#include "daemon_test_util.hpp"

using namespace dtest;

namespace {

const std::string kClient = "tc-tester";

json upload_text(const Http& h, const std::string& text, const std::string& name) {
  const auto r = h.request("POST", "/api/v1/files?name=" + name, text, {{"Content-Type", "application/octet-stream"}});
  EXPECT_TRUE(r.status == 201 || r.status == 200) << r.status << " " << r.body;
  return r.j();
}

json job(const Http& h, std::int64_t id) { return h.get("/api/v1/jobs/" + std::to_string(id)).j(); }
json machine(const Http& h, const std::string& m) { return h.get("/api/v1/machines/" + m).j(); }

bool ready(const Http& h, const std::string& m) { return h.get("/api/v1/machines/" + m).j()["link"] == "ready"; }

Http with_client(Http h) {
  h.headers["X-Client-Id"] = kClient;
  return h;
}

// T1 cuts a slow first move (the job streams for a while), then T2 (7.3 mm
// longer in the simulator's table) at the T + M0 our programs write, with
// the note before it, then a last move.
const char* kTwoTools =
    "G21 G90\nT1\nG0 Z5\nG1 X50 F100\n(finishing: 6 mm flat end mill)\nT2\nM0\nG1 X40 F500\nG1 Y5\nM2\n";

// A sim machine with two tools of unequal stick-out and a tool-length sensor.
cncstream::daemon::MachineConfig tool_machine(const std::string& name, const std::string& speed, bool sensor) {
  auto m = sim_machine(name, speed);
  m.sim_tool_table = "1=flat:6@30,2=flat:6@37.3";
  if (sensor) m.sim_tool_sensor = "-30,0,-10";
  m.tool_change.method = "sensor";
  m.tool_change.sensor_at = std::array<double, 2>{-30, 0};
  m.tool_change.probe_travel = 50;
  return m;
}

std::int64_t create(const Http& h, const std::string& m, const json& file, const json& tool_change = nullptr) {
  json body = {{"machine", m}, {"file", file["id"]}};
  if (!tool_change.is_null()) body["tool_change"] = tool_change;
  const auto r = h.post("/api/v1/jobs", body);
  EXPECT_EQ(r.status, 201) << r.body;
  const auto id = r.j()["id"].get<std::int64_t>();
  EXPECT_TRUE(wait_for([&] { return job(h, id)["state"] == "ready"; }, 30)) << job(h, id).dump();
  return id;
}

}  // namespace

TEST(DaemonToolChange, SensorChangeStopsAtThePromptJogsThereAndConfirmFinishesTheJob) {
  const auto dir = temp_dir("toolchange");
  auto cfg = test_config(dir);
  cfg.machines = {tool_machine("tc", "20", true)};
  RunningDaemon d(cfg);
  const Http h = with_client(d.http);
  ASSERT_TRUE(wait_for([&] { return ready(h, "tc"); }, 30));
  ASSERT_EQ(h.post("/api/v1/machines/tc/control").status, 200);
  const auto file = upload_text(h, kTwoTools, "two-tools.nc");
  // A bad override is a 400 naming the field.
  auto bad = h.post("/api/v1/jobs", {{"machine", "tc"}, {"file", file["id"]}, {"tool_change", {{"safe_z", "high"}}}});
  EXPECT_EQ(bad.status, 400);
  EXPECT_NE(bad.body.find("tool_change.safe_z"), std::string::npos) << bad.body;

  // The job asks for the plate and the machine has no plate position: a program that changes
  // tools is refused before it moves, naming the setting.
  const auto refused_id = create(h, "tc", file, {{"method", "plate"}});
  auto r = h.post("/api/v1/jobs/" + std::to_string(refused_id) + "/start");
  EXPECT_EQ(r.status, 409);
  EXPECT_NE(r.body.find("plate_at"), std::string::npos) << r.body;
  EXPECT_EQ(machine(h, "tc")["tool_change_settings"]["safe_z"], 50);  // a sim machine's default
  EXPECT_EQ(job(h, refused_id)["state"], "ready");
  // A ready job may start from a line (the page's "continue after line"); it names the line.
  const std::string plan_path = "/api/v1/jobs/" + std::to_string(refused_id) + "/resume-plan";
  EXPECT_EQ(h.post(plan_path, {{"from_line", -1}}).status, 400);
  r = h.post(plan_path, {{"from_line", 8}});
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(r.j()["from_line"], 8);

  // T2 is in the daemon's tool library: the prompt names it with its expected stick-out (T1 is not).
  r = h.post("/api/v1/tools", {{"number", 2}, {"name", "6 mm finisher"}, {"shape", "flat:6"}, {"flutes", 2}, {"stick_out", 37.3}});
  ASSERT_EQ(r.status, 201) << r.body;

  // The machine's sensor, at the job's own safe Z.
  const auto id = create(h, "tc", file, {{"safe_z", 30}});
  EXPECT_EQ(job(h, id)["tool_change"]["safe_z"], 30);
  WsClient ws;
  ASSERT_EQ(ws.connect(d.port(), "/api/v1/ws?client_id=" + kClient), 101);
  ws.send(json{{"type", "subscribe"}, {"machines", {"tc"}}});
  ASSERT_EQ(h.post("/api/v1/jobs/" + std::to_string(id) + "/start").status, 202);
  // While the job streams, a jog is refused.
  r = h.post("/api/v1/machines/tc/jog", {{"dir", {0, 0, 1}}, {"distance", 5}, {"feed", 1000}});
  EXPECT_EQ(r.status, 409) << r.body;
  EXPECT_NE(r.body.find("a job is running"), std::string::npos) << r.body;
  EXPECT_EQ(h.post("/api/v1/machines/tc/tool-change/confirm").status, 409);  // nothing asked yet

  // The prompt: in the WebSocket's tool_change frames and in the machine's state.
  const auto frame = ws.wait_message(
      [](const json& j) { return j["type"] == "tool_change" && !j["state"].is_null() && j["state"]["step"] == "mount_tool"; },
      60);
  ASSERT_TRUE(frame);
  const json tc = machine(h, "tc")["tool_change"];
  ASSERT_FALSE(tc.is_null());
  EXPECT_EQ(tc["step"], "mount_tool");
  EXPECT_EQ(tc["tool"], 2);
  EXPECT_EQ(tc["from_tool"], 1);
  EXPECT_EQ(tc["line"], 7);
  EXPECT_EQ(tc["method"], "sensor");
  EXPECT_TRUE(tc["operator_turn"].get<bool>());
  EXPECT_NE(tc["description"].get<std::string>().find("finishing"), std::string::npos) << tc.dump();
  EXPECT_NE(tc["prompt"]["text"].get<std::string>().find("mount T2"), std::string::npos) << tc.dump();
  ASSERT_TRUE(tc["library_tool"].is_object()) << tc.dump();
  EXPECT_EQ(tc["library_tool"]["number"], 2);
  EXPECT_EQ(tc["library_tool"]["name"], "6 mm finisher");
  EXPECT_EQ(tc["library_tool"]["shape"], "flat:6");
  EXPECT_DOUBLE_EQ(tc["library_tool"]["stick_out"].get<double>(), 37.3);
  EXPECT_EQ((*frame)["state"]["library_tool"]["name"], "6 mm finisher");  // the same on the WebSocket
  EXPECT_EQ(job(h, id)["state"], "running");

  // At the prompt the machine is the operator's: a step jog moves it.
  const double z0 = machine(h, "tc")["status"]["mpos"][2].get<double>();
  r = h.post("/api/v1/machines/tc/jog", {{"dir", {0, 0, -1}}, {"distance", 5}, {"feed", 1000}});
  ASSERT_EQ(r.status, 202) << r.body;
  ASSERT_TRUE(wait_for([&] {
    const json s = machine(h, "tc");
    return !s["jogging"].get<bool>() && std::abs(s["status"]["mpos"][2].get<double>() - (z0 - 5)) < 0.002;
  }, 20)) << machine(h, "tc").dump();

  // Confirm (the simulated operator mounts T2): measured, the offset written, the job goes on to its end.
  ASSERT_EQ(h.post("/api/v1/machines/tc/tool-change/confirm").status, 202);
  ASSERT_TRUE(wait_for([&] { return job(h, id)["state"] == "done"; }, 60)) << job(h, id).dump();
  EXPECT_TRUE(machine(h, "tc")["tool_change"].is_null());
  EXPECT_EQ(machine(h, "tc")["tool_in_spindle"], 2);
  // The new tool is 7.3 mm longer: the work offset's Z moved up by that much.
  ASSERT_TRUE(wait_for([&] { return !machine(h, "tc")["status"]["wco"].is_null(); }, 5));
  EXPECT_NEAR(machine(h, "tc")["status"]["wco"][2].get<double>(), 7.3, 0.01) << machine(h, "tc").dump();
  const auto record = ws.wait_message([](const json& j) { return j["type"] == "tool_change" && !j["record"].is_null(); }, 5);
  ASSERT_TRUE(record);
  EXPECT_TRUE((*record)["record"]["length_known"].get<bool>());
  const auto journal_id = job(h, id)["journal_id"].get<std::int64_t>();
  d.shutdown();
  cncstream::transport::Journal journal(cfg.journal);
  const auto rows = journal.tool_changes(journal_id);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].line, 7);
  EXPECT_EQ(rows[0].tool, 2);
  EXPECT_EQ(rows[0].method, "sensor");
  EXPECT_TRUE(rows[0].length_known);
  ASSERT_TRUE(rows[0].offset_z);
  EXPECT_NEAR(*rows[0].offset_z, 7.3, 0.01);
  std::filesystem::remove_all(dir);
}

// A program the daemon generates from library tools writes their numbers (roughing with tool 5,
// finishing with tool 3: T5, then T3), and the tool change names library tool 3 by its number.
TEST(DaemonToolChange, AGeneratedProgramsChangeNamesTheLibraryToolOfItsOperation) {
  const auto dir = temp_dir("toolchange-library");
  auto cfg = test_config(dir);
  auto gen = tool_machine("gen", "max", true);
  gen.sim_tool_table = "5=flat:6@30,3=ball:3@25";
  gen.tool_change.probe_travel = 100;  // the sensor (top at Z -10) is measured from the safe Z (50)
  cfg.machines = {gen};
  RunningDaemon d(cfg);
  const Http h = with_client(d.http);
  ASSERT_TRUE(wait_for([&] { return ready(h, "gen"); }, 30));
  ASSERT_EQ(h.post("/api/v1/machines/gen/control").status, 200);
  auto r = h.post("/api/v1/tools", {{"number", 3}, {"name", "3 mm ball"}, {"shape", "ball:3"}, {"stick_out", 25}});
  ASSERT_EQ(r.status, 201) << r.body;
  r = h.post("/api/v1/tools", {{"number", 5}, {"name", "6 mm rougher"}, {"shape", "flat:6"}, {"stick_out", 30}});
  ASSERT_EQ(r.status, 201) << r.body;
  // Another tool of the same shape as tool 3: the change names tool 3 by its number, not by shape.
  r = h.post("/api/v1/tools", {{"number", 1}, {"name", "not this one"}, {"shape", "ball:3"}, {"stick_out", 40}});
  ASSERT_EQ(r.status, 201) << r.body;
  std::string pyramid = "solid p\n";
  const char* base[5] = {"0 0 0", "20 0 0", "20 20 0", "0 20 0", "0 0 0"};
  for (int i = 0; i < 4; ++i)
    pyramid += std::string("facet normal 0 0 0\nouter loop\nvertex ") + base[i] + "\nvertex " + base[i + 1] +
               "\nvertex 10 10 5\nendloop\nendfacet\n";
  pyramid += "facet normal 0 0 -1\nouter loop\nvertex 0 0 0\nvertex 20 20 0\nvertex 20 0 0\nendloop\nendfacet\n"
             "facet normal 0 0 -1\nouter loop\nvertex 0 0 0\nvertex 0 20 0\nvertex 20 20 0\nendloop\nendfacet\nendsolid p\n";
  const auto file = upload_text(h, pyramid, "pyramid.stl");
  r = h.post("/api/v1/jobs", {{"machine", "gen"},
                              {"file", file["id"]},
                              {"params", {{"tool", "T3"}, {"rough", "5"}, {"stepover", 1}, {"feed", 2000},
                                          {"plunge_feed", 500}, {"rpm", 18000}}}});
  ASSERT_EQ(r.status, 201) << r.body;
  const auto id = r.j()["id"].get<std::int64_t>();
  ASSERT_TRUE(wait_for([&] { return job(h, id)["state"] == "ready"; }, 60)) << job(h, id).dump();
  // The canonical params keep the library's numbers beside the specs; the program writes them.
  EXPECT_EQ(job(h, id)["params"]["tool_number"], 3) << job(h, id).dump();
  EXPECT_EQ(job(h, id)["params"]["rough_tool_number"], 5);
  const std::string gcode = h.get("/api/v1/jobs/" + std::to_string(id) + "/gcode").body;
  const auto t5 = gcode.find("\nT5\n"), t3 = gcode.find("\nT3\n");
  ASSERT_NE(t5, std::string::npos) << gcode.substr(0, 2000);
  ASSERT_NE(t3, std::string::npos);
  EXPECT_LT(t5, t3);
  EXPECT_EQ(gcode.find("\nT1\n"), std::string::npos);
  EXPECT_EQ(gcode.find("\nT2\n"), std::string::npos);
  ASSERT_EQ(h.post("/api/v1/jobs/" + std::to_string(id) + "/start").status, 202);
  json tc;
  ASSERT_TRUE(wait_for([&] {
    tc = machine(h, "gen")["tool_change"];
    return !tc.is_null() && tc["step"] == "mount_tool";
  }, 60)) << job(h, id).dump();
  EXPECT_EQ(tc["tool"], 3) << tc.dump();
  ASSERT_TRUE(tc["library_tool"].is_object()) << tc.dump();
  EXPECT_EQ(tc["library_tool"]["number"], 3) << tc.dump();
  EXPECT_EQ(tc["library_tool"]["name"], "3 mm ball");
  EXPECT_DOUBLE_EQ(tc["library_tool"]["stick_out"].get<double>(), 25);
  ASSERT_EQ(h.post("/api/v1/machines/gen/tool-change/decline").status, 202);
  ASSERT_TRUE(wait_for([&] { return job(h, id)["state"] == "failed"; }, 30)) << job(h, id).dump();
  d.shutdown();
  std::filesystem::remove_all(dir);
}

TEST(DaemonToolChange, DeclineAndAMissingSensorEndTheJobWithTheLengthUnknown) {
  const auto dir = temp_dir("toolchange-fail");
  auto cfg = test_config(dir);
  auto with = tool_machine("with", "max", true), without = tool_machine("without", "max", false);
  with.tool_change.safe_z = 30;
  without.tool_change.safe_z = 30;
  cfg.machines = {with, without};
  RunningDaemon d(cfg);
  const Http h = with_client(d.http);
  ASSERT_TRUE(wait_for([&] { return ready(h, "with") && ready(h, "without"); }, 30));
  const auto file = upload_text(h, kTwoTools, "two-tools.nc");
  for (const char* m : {"with", "without"}) ASSERT_EQ(h.post(std::string("/api/v1/machines/") + m + "/control").status, 200);

  // No sensor where the settings say: the reference never triggers; the job fails before any prompt.
  const auto lost = create(h, "without", file);
  ASSERT_EQ(h.post("/api/v1/jobs/" + std::to_string(lost) + "/start").status, 202);
  ASSERT_TRUE(wait_for([&] { return job(h, lost)["state"] == "failed"; }, 60)) << job(h, lost).dump();
  EXPECT_NE(job(h, lost)["message"].get<std::string>().find("never triggered"), std::string::npos) << job(h, lost).dump();

  // Declined at the mount prompt: the job stops there.
  const auto declined = create(h, "with", file);
  ASSERT_EQ(h.post("/api/v1/jobs/" + std::to_string(declined) + "/start").status, 202);
  ASSERT_TRUE(wait_for([&] {
    const json tc = machine(h, "with")["tool_change"];
    return !tc.is_null() && tc["step"] == "mount_tool";
  }, 60));
  EXPECT_TRUE(machine(h, "with")["tool_change"]["library_tool"].is_null());  // T2 is in no library here
  ASSERT_EQ(h.post("/api/v1/machines/with/tool-change/decline").status, 202);
  ASSERT_TRUE(wait_for([&] { return job(h, declined)["state"] == "failed"; }, 30)) << job(h, declined).dump();
  EXPECT_NE(job(h, declined)["message"].get<std::string>().find("declined"), std::string::npos);
  EXPECT_EQ(h.post("/api/v1/machines/with/tool-change/sideways").status, 400);
  const auto lost_journal = job(h, lost)["journal_id"].get<std::int64_t>();
  const auto declined_journal = job(h, declined)["journal_id"].get<std::int64_t>();
  d.shutdown();
  cncstream::transport::Journal journal(cfg.journal);
  for (const auto jid : {lost_journal, declined_journal}) {
    const auto rows = journal.tool_changes(jid);
    ASSERT_EQ(rows.size(), 1u) << jid;
    EXPECT_FALSE(rows[0].length_known);
  }
  std::filesystem::remove_all(dir);
}

TEST(DaemonToolChange, TheMachinesToolChangeTableIsReadAndABadFieldNamesTheFileAndLine) {
  using cncstream::daemon::parse_config;
  const auto c = parse_config(
      "[[machine]]\nname = \"r\"\nport = \"sim\"\nsim_tool_table = \"1=flat:6@30\"\nsim_probe_surface_z = 10\n"
      "[machine.tool_change]\nmethod = \"plate\"\nsafe_z = -1\nplate_at = [20, 25.5]\nplate_thickness = 5\n",
      "d.toml");
  ASSERT_EQ(c.machines.size(), 1u);
  const auto& tc = c.machines[0].tool_change;
  EXPECT_EQ(tc.method, "plate");
  ASSERT_TRUE(tc.safe_z && tc.plate_at);
  EXPECT_EQ(*tc.safe_z, -1);
  EXPECT_EQ((*tc.plate_at)[1], 25.5);
  EXPECT_EQ(tc.plate_thickness, 5);
  EXPECT_EQ(c.machines[0].sim_probe_surface_z, 10);
  const auto routine = cncstream::daemon::routine_config(tc, true);
  ASSERT_TRUE(routine);
  EXPECT_EQ(routine->probe_y, 25.5);
  try {
    parse_config("[[machine]]\nname = \"r\"\nport = \"sim\"\n[machine.tool_change]\nmethod = \"laser\"\n", "d.toml");
    FAIL() << "an unknown method was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("d.toml:4"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("machine.tool_change.method"), std::string::npos) << e.what();
  }
  // Pause needs nothing; sensor without its position is refused only for a program that changes tools.
  cncstream::daemon::ToolChangeSettings s;
  s.method = "pause";
  EXPECT_FALSE(cncstream::daemon::routine_config(s, true));
  s.method = "sensor";
  s.safe_z = 0;
  EXPECT_TRUE(cncstream::daemon::routine_config(s, false));
  EXPECT_THROW(cncstream::daemon::routine_config(s, true), std::invalid_argument);
}

// The tool routines outside a job (POST /machines/{m}/routines/tool_*): the
// reference kept by the daemon per machine, a change to a 7.3 mm longer tool
// written and read back, the check; refused while a job runs.
TEST(DaemonToolChange, RoutinesOutsideAJobMeasureChangeAndCheckWithTheMachinesReference) {
  const auto dir = temp_dir("toolroutines");
  auto cfg = test_config(dir);
  auto tm = tool_machine("rt", "20", true);
  tm.tool_change.safe_z = 30;
  cfg.machines = {tm};
  RunningDaemon d(cfg);
  const Http h = with_client(d.http);
  ASSERT_TRUE(wait_for([&] { return ready(h, "rt"); }, 30));
  const std::string base = "/api/v1/machines/rt/";
  EXPECT_EQ(h.post(base + "routines/tool_measure").status, 409);  // control first
  ASSERT_EQ(h.post(base + "control").status, 200);
  EXPECT_TRUE(machine(h, "rt")["tool_reference"].is_null());
  EXPECT_TRUE(machine(h, "rt")["routine"].is_null());
  EXPECT_EQ(h.post(base + "routines/sideways").status, 400);
  auto r = h.post(base + "routines/tool_change", json::object());
  EXPECT_EQ(r.status, 400);
  EXPECT_NE(r.body.find("tool"), std::string::npos) << r.body;
  EXPECT_EQ(h.post(base + "routines/tool_change", {{"tool", 2.5}}).status, 400);
  EXPECT_EQ(h.post(base + "routines/tool_measure", {{"tool_change", {{"method", "laser"}}}}).status, 400);
  EXPECT_EQ(h.post(base + "routine/confirm").status, 409);  // nothing asked
  // Nothing measured: the check is refused, naming why.
  r = h.post(base + "routines/tool_check", {{"in_spindle", 1}});
  EXPECT_EQ(r.status, 409);
  EXPECT_NE(r.body.find("no measured length of T1"), std::string::npos) << r.body;

  WsClient ws;
  ASSERT_EQ(ws.connect(d.port(), "/api/v1/ws?client_id=" + kClient), 101);
  ws.send(json{{"type", "subscribe"}, {"machines", {"rt"}}});
  const auto ended = [&ws] {
    return ws.wait_message([](const json& j) { return j["type"] == "routine" && !j["succeeded"].is_null(); }, 60);
  };
  ASSERT_EQ(h.post(base + "routines/tool_measure", {{"in_spindle", 1}}).status, 202);
  auto end = ended();
  ASSERT_TRUE(end);
  ASSERT_TRUE((*end)["succeeded"].get<bool>()) << end->dump();
  json ref = machine(h, "rt")["tool_reference"];
  ASSERT_FALSE(ref.is_null());
  EXPECT_EQ(ref["tool"], 1);
  EXPECT_EQ(ref["method"], "sensor");

  // Change to T2: the prompt in the machine's state, confirm, measured and written.
  ASSERT_EQ(h.post(base + "routines/tool_change", {{"tool", 2}}).status, 202);
  ASSERT_TRUE(wait_for([&] {
    const json rt = machine(h, "rt")["routine"];
    return !rt.is_null() && !rt["prompt"].is_null() && rt["prompt"]["kind"] == "mount_tool";
  }, 60)) << machine(h, "rt").dump();
  EXPECT_EQ(machine(h, "rt")["routine"]["name"], "tool change");
  EXPECT_EQ(machine(h, "rt")["routine"]["prompt"]["tool"], 2);
  // Another routine meanwhile: refused; at the prompt the operator may jog (confirm waits for it to end).
  EXPECT_EQ(h.post(base + "routines/tool_check").status, 409);
  EXPECT_EQ(h.post(base + "actions/home").status, 409);
  ASSERT_EQ(h.post(base + "jog", {{"dir", {0, 0, 1}}, {"distance", 1}, {"feed", 100}}).status, 202);
  ASSERT_TRUE(wait_for([&] { return !machine(h, "rt")["jogging"].get<bool>(); }, 20));
  ASSERT_TRUE(wait_for([&] { return h.post(base + "routine/confirm").status == 202; }, 20));
  end = ended();
  ASSERT_TRUE(end);
  ASSERT_TRUE((*end)["succeeded"].get<bool>()) << end->dump();
  EXPECT_TRUE((*end)["record"]["length_known"].get<bool>());
  EXPECT_NEAR((*end)["record"]["offset_z"].get<double>(), 7.3, 0.002);
  const json st = machine(h, "rt");
  EXPECT_EQ(st["tool_in_spindle"], 2);
  EXPECT_NEAR(st["status"]["wco"][2].get<double>(), 7.3, 0.01) << st.dump();
  ref = st["tool_reference"];
  EXPECT_EQ(ref["measured_tool"], 2);
  EXPECT_NEAR(ref["measured_trigger_z"].get<double>() - ref["trigger_z"].get<double>(), 7.3, 0.002);

  // The broken-bit check: T2 is as measured.
  ASSERT_EQ(h.post(base + "routines/tool_check", {{"tolerance", 0.05}}).status, 202);
  end = ended();
  ASSERT_TRUE(end);
  EXPECT_TRUE((*end)["succeeded"].get<bool>()) << end->dump();
  EXPECT_NE((*end)["text"].get<std::string>().find("T2 is within 0.050 mm"), std::string::npos) << end->dump();

  // While a job runs, no routine starts.
  const auto file = upload_text(h, "G21 G90\nG1 X50 F100\nG1 X0\nM2\n", "slow.nc");
  const auto id = create(h, "rt", file);
  ASSERT_EQ(h.post("/api/v1/jobs/" + std::to_string(id) + "/start").status, 202);
  ASSERT_TRUE(wait_for([&] { return machine(h, "rt")["job_active"].get<bool>(); }, 10));
  r = h.post(base + "routines/tool_check");
  EXPECT_EQ(r.status, 409);
  EXPECT_NE(r.body.find("a job is running"), std::string::npos) << r.body;
  ASSERT_EQ(h.post(base + "stop").status, 202);
  ASSERT_TRUE(wait_for([&] { return !machine(h, "rt")["job_active"].get<bool>(); }, 30));
  // The stop reset the controller: the reference is forgotten.
  ASSERT_TRUE(wait_for([&] { return machine(h, "rt")["tool_reference"].is_null(); }, 10)) << machine(h, "rt").dump();
  d.shutdown();
  std::filesystem::remove_all(dir);
}

TEST(DaemonToolChange, AJobsOwnToolChangeSettingsSurviveARestart) {
  // The machine measures with its sensor; the job asks for the plate without
  // saying where it lies. Before and after a restart the job's own settings
  // decide: its start is refused naming plate_at (the machine's sensor would
  // have run the change with settings the job did not ask for).
  const auto dir = temp_dir("toolchange-restart");
  auto cfg = test_config(dir);
  auto m = tool_machine("keep", "max", true);
  m.tool_change.safe_z = 30;
  cfg.machines = {m};
  std::int64_t id = 0;
  const json asked = {{"method", "plate"}, {"probe_travel", 20}};
  {
    RunningDaemon d(cfg);
    const Http h = with_client(d.http);
    ASSERT_TRUE(wait_for([&] { return ready(h, "keep"); }, 30));
    const auto file = upload_text(h, kTwoTools, "two-tools.nc");
    id = create(h, "keep", file, asked);
    EXPECT_EQ(job(h, id)["tool_change"], asked);
    d.shutdown();
  }
  RunningDaemon d2(cfg);
  const Http h = with_client(d2.http);
  ASSERT_TRUE(wait_for([&] { return ready(h, "keep"); }, 30));
  ASSERT_TRUE(wait_for([&] { return job(h, id)["state"] == "ready"; }, 30)) << job(h, id).dump();
  EXPECT_EQ(job(h, id)["tool_change"], asked) << job(h, id).dump();
  ASSERT_EQ(h.post("/api/v1/machines/keep/control").status, 200);
  const auto r = h.post("/api/v1/jobs/" + std::to_string(id) + "/start");
  EXPECT_EQ(r.status, 409) << r.body;
  EXPECT_NE(r.body.find("plate_at"), std::string::npos) << r.body;
  d2.shutdown();
  std::filesystem::remove_all(dir);
}

TEST(DaemonToolChange, GrblHalsOwnChangeZeroedAtThePromptInItsToolState) {
  // A machine simulating grblHAL ($341=0) with the method controller: the
  // prompt comes with the controller in its Tool state; Probe Z is refused
  // there (error:40), a jog and Zero Z are not; confirm ends the change.
  const auto dir = temp_dir("toolchange-hal");
  auto cfg = test_config(dir);
  auto m = tool_machine("hal", "max", false);
  m.sim_firmware = "grblhal";
  m.tool_change.method = "controller";
  m.tool_change.safe_z = 30;
  cfg.machines = {m};
  RunningDaemon d(cfg);
  const Http h = with_client(d.http);
  ASSERT_TRUE(wait_for([&] { return ready(h, "hal"); }, 30));
  ASSERT_EQ(machine(h, "hal")["profile"], "grblhal");
  ASSERT_EQ(h.post("/api/v1/machines/hal/control").status, 200);
  const auto file = upload_text(h, kTwoTools, "two-tools.nc");
  const auto id = create(h, "hal", file);
  ASSERT_EQ(h.post("/api/v1/jobs/" + std::to_string(id) + "/start").status, 202);
  ASSERT_TRUE(wait_for([&] {
    const json tc = machine(h, "hal")["tool_change"];
    return !tc.is_null() && tc["step"] == "zero_manually";
  }, 60)) << machine(h, "hal").dump();
  EXPECT_EQ(machine(h, "hal")["tool_change"]["method"], "controller");
  EXPECT_EQ(machine(h, "hal")["status"]["state"], "Tool");
  auto r = h.post("/api/v1/machines/hal/actions/probe_z");
  EXPECT_EQ(r.status, 409) << r.body;
  EXPECT_NE(r.body.find("error:40"), std::string::npos) << r.body;
  const double z0 = machine(h, "hal")["status"]["mpos"][2].get<double>();
  r = h.post("/api/v1/machines/hal/jog", {{"dir", {0, 0, -1}}, {"distance", 4}, {"feed", 1000}});
  ASSERT_EQ(r.status, 202) << r.body;
  ASSERT_TRUE(wait_for([&] {
    const json s = machine(h, "hal");
    return !s["jogging"].get<bool>() && s["status"]["state"] == "Tool" &&
           std::abs(s["status"]["mpos"][2].get<double>() - (z0 - 4)) < 0.002;
  }, 20)) << machine(h, "hal").dump();
  r = h.post("/api/v1/machines/hal/actions/zero_axes", {{"axes", "Z"}});
  ASSERT_EQ(r.status, 202) << r.body;
  ASSERT_EQ(h.post("/api/v1/machines/hal/tool-change/confirm").status, 202);
  ASSERT_TRUE(wait_for([&] { return job(h, id)["state"] == "done"; }, 60)) << job(h, id).dump();
  EXPECT_EQ(machine(h, "hal")["tool_in_spindle"], 2);
  const auto journal_id = job(h, id)["journal_id"].get<std::int64_t>();
  d.shutdown();
  cncstream::transport::Journal journal(cfg.journal);
  const auto rows = journal.tool_changes(journal_id);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].method, "controller");
  EXPECT_TRUE(rows[0].length_known);
  ASSERT_TRUE(rows[0].offset_z);
  EXPECT_NEAR(*rows[0].offset_z, z0 - 4, 0.002);
  std::filesystem::remove_all(dir);
}
