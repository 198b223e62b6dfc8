#include "daemon_handoff.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <fstream>
#include <iostream>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>
#include <vector>

#include "cli_common.hpp"
#include "cncstream/cam/cutter.hpp"
#include "cncstream/gcode/gcode_writer.hpp"
#include "cncstream/jobs/output_file.hpp"
#include "cncstream/protocol/firmware_profile.hpp"
#include "keyboard_control.hpp"
#include "live_panel.hpp"

namespace cncstream::app {

namespace {

using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

// Ctrl-C while following a job on the daemon: the first asks the daemon for
// the controlled stop (as a local run does); the second gives SIGINT back to
// the system, so a third ends the process (the job goes on stopping there).
volatile std::sig_atomic_t g_handoff_sigints = 0;
extern "C" void handoff_on_sigint(int) {
  g_handoff_sigints = g_handoff_sigints + 1;
  // If this fails, a third Ctrl-C is only counted again: nothing to do here.
  if (g_handoff_sigints >= 2) (void)std::signal(SIGINT, SIG_DFL);
}

// The local run's words for how a job ended.
std::string handoff_outcome_word(const std::string& state) { return state == "done" ? "completed" : state; }

std::optional<protocol::Axes> axes_of(const json& j, const char* key) {
  if (!j.is_object() || !j.contains(key) || !j[key].is_array() || j[key].size() < 3) return std::nullopt;
  protocol::Axes a{};
  for (std::size_t i = 0; i < 3; ++i) a[i] = j[key][i].is_number() ? j[key][i].get<double>() : 0.0;
  return a;
}

std::string read_whole_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(path + ": cannot read");
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

// The key thread's requests, carried out on the main thread (which owns the
// HTTP client and the display).
class ActionQueue {
 public:
  void push(std::function<void()> fn) {
    std::lock_guard<std::mutex> g(mu_);
    q_.push_back(std::move(fn));
  }
  std::vector<std::function<void()>> take() {
    std::lock_guard<std::mutex> g(mu_);
    std::vector<std::function<void()>> out;
    out.swap(q_);
    return out;
  }

 private:
  std::mutex mu_;
  std::vector<std::function<void()>> q_;
};

}  // namespace

std::optional<DaemonOwner> daemon_owning_port(const std::string& port) {
  if (port == "sim" || port == "auto") return std::nullopt;
  const auto owner = transport::port_owner(port);
  if (!owner) return std::nullopt;
  if (owner->api.empty()) throw transport::PortBusyError(transport::busy_message(port, *owner), *owner);
  DaemonOwner d{*owner, parse_daemon_address(owner->api)};
  const DaemonClient probe(d.address, {}, daemon_token_from_env());
  try {
    const json health = probe.get("/api/v1/health", 3);
    if (!(health.contains("ok") && health["ok"] == true)) throw std::runtime_error("it answers, but not ok");
  } catch (const std::exception& e) {
    throw std::runtime_error(transport::busy_message(port, *owner) + "; its API does not answer (" + e.what() +
                             "), so the job cannot be handed to it");
  }
  return d;
}

json job_params_from(const ToolpathOptions& tp) {
  json p;
  p["tool"] = tp.tool;
  p["stepover"] = tp.stepover;
  p["step"] = tp.step;
  p["direction"] = tp.direction;
  p["strategy"] = tp.strategy;
  p["steep_angle"] = tp.steep_angle;
  p["scallop"] = tp.scallop ? json(*tp.scallop) : json(nullptr);
  p["feed"] = tp.feed;
  p["plunge_feed"] = tp.plunge_feed;
  p["rpm"] = tp.rpm;
  // A material: the daemon computes what the operator did not give, within its machine's rates.
  if (!tp.material.empty()) {
    p["material"] = tp.material;
    if (!tp.feed_given) p.erase("feed");
    if (!tp.plunge_feed_given) p.erase("plunge_feed");
    if (!tp.rpm_given) p.erase("rpm");
  }
  p["safe_z"] = tp.safe_z ? json(*tp.safe_z) : json(nullptr);
  p["tolerance"] = tp.tolerance;
  p["arcs"] = tp.arcs;
  p["controller_arc_tolerance"] = tp.controller_arc_tolerance;
  if (tp.bounds.empty()) {
    p["bounds"] = nullptr;
  } else {
    const auto b = parse_bounds(tp.bounds);
    p["bounds"] = json::array({b[0], b[1], b[2], b[3]});
  }
  p["floor"] = tp.floor ? json(*tp.floor) : json(nullptr);
  p["origin"] = tp.origin;
  p["z_zero"] = tp.z_zero;
  if (tp.part.units == "m") {
    p["units"] = "mm";
    p["scale"] = tp.part.scale * 1000.0;
  } else {
    p["units"] = tp.part.units;
    p["scale"] = tp.part.scale;
  }
  auto opt = [](const std::optional<double>& v) { return v ? json(*v) : json(nullptr); };
  p["stock"] = tp.stock;
  p["max_depth"] = opt(tp.max_depth);
  p["rough"] = tp.rough.empty() ? json(nullptr) : json(tp.rough);
  p["rough_max_depth"] = opt(tp.rough_max_depth);
  p["leave"] = tp.leave;
  p["step_down"] = opt(tp.step_down);
  p["rough_stepover"] = tp.rough_stepover;
  p["rough_feed"] = opt(tp.rough_feed);
  p["tool_change"] = tp.tool_change;
  return p;
}

int hand_off_to_daemon(const DaemonOwner& daemon, const HandoffJob& job, const ConnectionOptions& c) {
  if (c.check || c.check_only)
    throw std::invalid_argument("--check and --check-only are not available when the daemon runs the job (" +
                                c.port + " is owned by " + daemon.owner.describe() + ")");
  const std::string client_id = "cncstream-cli-" + std::to_string(::getpid());
  const DaemonClient api(daemon.address, client_id, daemon_token_from_env());
  std::cerr << c.port << " is owned by " << daemon.owner.describe() << ": handing the job to it\n";
  if (!c.profile.empty() || c.serial != "115200")
    std::cerr << "note: --serial and --profile are the daemon's to choose (its configuration); ignored here\n";
  if (c.no_journal || !c.journal.empty())
    std::cerr << "note: the daemon journals the job in its own journal (--journal and --no-journal do not apply)\n";

  // The daemon's machine on this port (its configuration may name it by
  // another path, e.g. /dev/serial/by-id/...).
  const json machines = api.get("/api/v1/machines");
  std::string machine;
  const json list = machines.contains("machines") && machines["machines"].is_array() ? machines["machines"] : json::array();
  for (const auto& m : list)
    if (transport::resolve_device(str_or(m, "port")) == daemon.owner.device) machine = str_or(m, "name");
  if (machine.empty())
    throw std::runtime_error("the daemon at " + daemon.address.url() + " owns " + c.port + " but lists no machine on " +
                             daemon.owner.device);
  const std::string mpath = "/api/v1/machines/" + url_encode(machine);

  // Control first: starting, and cancelling the job if the operator says no, need it.
  try {
    api.post(mpath + "/control", json{{"force", false}});
  } catch (const DaemonError& e) {
    if (e.code() != "control_held") throw;
    throw std::runtime_error("machine '" + machine + "' on the daemon is controlled by another client (" + e.what() +
                             "): release it there first");
  }
  bool have_control = true;
  std::int64_t job_id = 0;
  bool started = false;
  auto release = [&] {
    if (job_id && !started) {
      try {
        api.post("/api/v1/jobs/" + std::to_string(job_id) + "/cancel");
      } catch (const std::exception&) {
      }
    }
    if (have_control) {
      try {
        api.del(mpath + "/control");
      } catch (const std::exception&) {
      }
      have_control = false;
    }
  };
  struct Guard {
    std::function<void()> fn;
    ~Guard() { fn(); }
  } guard{release};

  const std::string label = std::filesystem::path(job.file).filename().string();
  const json file = api.upload("/api/v1/files?name=" + url_encode(label), read_whole_file(job.file));
  json create{{"machine", machine}, {"file", str_or(file, "id")}};
  if (job.stl) create["params"] = job_params_from(job.tp);
  json j = api.post("/api/v1/jobs", create);
  job_id = static_cast<std::int64_t>(num_or(j, "id", 0));
  if (!job_id) throw std::runtime_error("the daemon created no job (answer: " + j.dump() + ")");
  const std::string jpath = "/api/v1/jobs/" + std::to_string(job_id);
  std::cerr << "daemon job #" << job_id << " on machine '" << machine << "'\n";

  g_handoff_sigints = 0;
  auto* previous = std::signal(SIGINT, handoff_on_sigint);
  struct RestoreSignal {
    decltype(previous) p;
    ~RestoreSignal() {
      if (p != SIG_ERR) (void)std::signal(SIGINT, p);  // valid, so it cannot fail
    }
  } restore{previous};

  // Generation (STL): wait for the program, saying which stage it is in.
  std::string stage;
  const auto gen_start = Clock::now();
  for (;;) {
    const std::string st = str_or(j, "state");
    if (st == "ready") break;
    if (job_state_is_final(st)) {
      std::cerr << "cncstream: the daemon's job #" << job_id << " " << st << " before it ran: "
                << str_or(j, "message", "(no message)") << "\n";
      return 1;
    }
    if (g_handoff_sigints > 0) {
      std::cerr << "interrupted: cancelling daemon job #" << job_id << "\n";
      return 1;  // the guard cancels it
    }
    if (c.timeout_s > 0 && std::chrono::duration<double>(Clock::now() - gen_start).count() > c.timeout_s) {
      std::cerr << "cncstream: time-out: the daemon's job #" << job_id << " was not ready within " << c.timeout_s
                << " s\n";
      return 1;
    }
    // A queued job (kept from before a daemon restart) is generated on
    // request; one that started generating meanwhile refuses, which is fine.
    if (st == "queued") {
      try {
        j = api.post(jpath + "/generate");
      } catch (const DaemonError&) {
      }
    }
    const std::string now_stage = str_or(obj_or(j, "generation"), "stage");
    if (st == "generating" && !now_stage.empty() && now_stage != "queued" && now_stage != "done" &&
        now_stage != stage) {
      stage = now_stage;
      std::cerr << "daemon: " << stage << "...\n";
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    j = api.get(jpath);
  }

  const json program = obj_or(j, "program");
  const long total_lines = static_cast<long>(num_or(program, "lines", 0));
  const double estimated_s = num_or(program, "estimated_s", -1);
  const std::string est_text = estimated_s >= 0 ? format_duration(estimated_s) : std::string("unknown");
  if (job.stl) {
    const cam::Cutter cutter = cam::parse_cutter_spec(job.tp.tool);
    const json gen = obj_or(j, "generation");
    const bool cached = gen.contains("cached") && gen["cached"].is_boolean() && gen["cached"].get<bool>();
    std::cout << "plan for " << job.file << " (tool path by the daemon at " << daemon.address.url()
              << (cached ? ", from its cache" : "") << "):\n"
              << "  tool: " << cutter.description() << " [" << cutter.spec() << "]\n";
    // The daemon's operations (roughing, finishing ...) and why.
    if (program.contains("operations") && program["operations"].is_array())
      for (const auto& op : program["operations"])
        if (op.is_object())
          std::cout << "  " << str_or(op, "name") << ": T" << static_cast<long>(num_or(op, "tool", 0)) << " "
                    << str_or(op, "cutter") << ", " << static_cast<long>(num_or(op, "lines", 0)) << " lines, "
                    << str_or(op, "detail") << "\n";
    if (program.contains("notes") && program["notes"].is_array())
      for (const auto& n : program["notes"])
        if (n.is_string()) std::cout << "  " << n.get<std::string>() << "\n";
    std::cout << "  feed " << format_gcode_number(job.tp.feed) << " mm/min, plunge " << format_gcode_number(job.tp.plunge_feed)
              << " mm/min\n"
              << "  work origin: XY at the part's " << job.tp.origin << ", Z0 at the part's " << job.tp.z_zero
              << " (set G54 there before cutting)\n"
              << "  program: daemon job #" << job_id << ", " << total_lines << " lines\n"
              << "  estimated machining time: " << est_text << " (the daemon's estimate for machine '" << machine
              << "')\n";
    if (!job.output.empty()) {
      jobs::write_text_file_atomically(job.output, api.get_text(jpath + "/gcode"));
      std::cout << "  program also written to " << job.output << "\n";
    }
    std::cout << std::flush;
    if (!confirm("Start machining on " + c.port + " (daemon job #" + std::to_string(job_id) + ")?", c.yes)) return 2;
  } else {
    std::cout << job.file << ": " << total_lines << " lines, estimated machining time " << est_text
              << " (the daemon's estimate for machine '" << machine << "')" << std::endl;
  }

  // Follow over the WebSocket, subscribed before the start so nothing is missed.
  std::unique_ptr<DaemonSocket> ws;
  try {
    ws = std::make_unique<DaemonSocket>(api);
    ws->send(json{{"type", "subscribe"}, {"machines", json::array({machine})}, {"id", 1}});
  } catch (const std::exception& e) {
    std::cerr << "note: no live status from the daemon (" << e.what() << "); following the job by polling\n";
    ws.reset();
  }
  double capacity = 128;
  try {
    capacity = num_or(obj_or(api.get(mpath), "buffer"), "capacity", 128);
  } catch (const std::exception&) {
  }

  // The daemon may still be identifying the controller (just opened, or
  // reconnecting): a local run waits for it too before starting.
  {
    const auto ready_by = Clock::now() + std::chrono::seconds(30);
    std::string link;
    for (;;) {
      link = str_or(api.get(mpath), "link");
      if (link == "ready") break;
      if (Clock::now() >= ready_by || g_handoff_sigints > 0) {
        std::cerr << "cncstream: machine '" << machine << "' on the daemon is not ready (link " << link
                  << "): job #" << job_id << " not started\n";
        return 1;  // the guard cancels the job
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
  try {
    j = api.post(jpath + "/start");
  } catch (const DaemonError& e) {
    std::cerr << "cncstream: the daemon did not start job #" << job_id << ": " << e.what() << "\n";
    return 1;  // the guard cancels the job: it was this command's
  }
  started = true;

  const bool tty = ::isatty(STDERR_FILENO);
  LivePanel panel(stderr, tty, c.progress_interval_s);
  const std::string title = label + " -> " + c.port + " (daemon job #" + std::to_string(job_id) + ", " + machine + ")";
  JobView view;
  view.title = title;
  view.total_lines = total_lines;
  view.job_state = "running";
  const auto t0 = Clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };

  ActionQueue actions;
  std::string job_state = str_or(j, "state", "running");
  auto call = [&](const std::string& what, const std::function<void()>& fn) {
    try {
      fn();
    } catch (const std::exception& e) {
      panel.message(what + ": " + e.what());
    }
  };
  auto stop = [&] { call("stop", [&] { api.post(jpath + "/stop"); }); };
  JobKeyActions keys_to_api;
  keys_to_api.toggle_pause = [&] {
    actions.push([&] {
      call("hold/resume", [&] { api.post(jpath + (job_state == "held" ? "/resume" : "/hold")); });
    });
  };
  keys_to_api.stop = [&] { actions.push(stop); };
  keys_to_api.realtime = [&](protocol::Realtime r) {
    const std::string command = protocol::realtime_key(r);
    actions.push([&, command] { call(command, [&] { api.post(mpath + "/realtime", json{{"command", command}}); }); });
  };
  auto keys = std::make_unique<KeyboardControl>(keys_to_api);
  if (!keys->active()) keys.reset();
  const bool interactive = keys != nullptr;

  json last_progress = obj_or(j, "progress");
  std::string message = str_or(j, "message");
  std::optional<std::int64_t> journal_id;
  bool stop_sent = false;
  int sigints_seen = 0;
  auto apply_job = [&](const json& m) {
    job_state = str_or(m, "state", job_state);
    if (m.contains("progress") && m["progress"].is_object()) last_progress = m["progress"];
    message = str_or(m, "message", message);
    if (m.contains("journal_id") && m["journal_id"].is_number_integer()) journal_id = m["journal_id"].get<std::int64_t>();
    view.job_state = handoff_outcome_word(job_state);  // "completed", as a local run says
    view.line = static_cast<long>(num_or(last_progress, "last_answered_line", double(view.line)));
    const double eta = num_or(m, "eta_s", num_or(last_progress, "eta_s", -1));
    view.eta_s = eta >= 0 ? std::optional<double>(eta) : std::nullopt;
  };
  bool status_has_rx = false;
  auto apply_status = [&](const json& s) {
    view.machine_state = str_or(s, "state_text", str_or(s, "state"));
    view.wpos = axes_of(s, "wpos");
    view.mpos = axes_of(s, "mpos");
    if (s.contains("overrides") && s["overrides"].is_array() && s["overrides"].size() == 3)
      view.overrides = std::array<int, 3>{s["overrides"][0].get<int>(), s["overrides"][1].get<int>(),
                                          s["overrides"][2].get<int>()};
    const double rx_free = num_or(obj_or(s, "buffer"), "rx_free", -1);
    if (rx_free >= 0 && capacity > 0) {
      view.buffer_fill = std::clamp(1.0 - rx_free / capacity, 0.0, 1.0);
      status_has_rx = true;
    }
  };
  // Controllers that do not report Bf: the daemon's count of bytes in
  // flight, as a local run shows.
  auto apply_machine = [&](const json& ms) {
    if (ms.contains("status") && ms["status"].is_object()) apply_status(ms["status"]);
    const json b = obj_or(ms, "buffer");
    const double in_flight = num_or(b, "in_flight", -1), cap = num_or(b, "capacity", capacity);
    if (!status_has_rx && in_flight >= 0 && cap > 0) view.buffer_fill = std::clamp(in_flight / cap, 0.0, 1.0);
  };

  auto last_poll = Clock::now() - std::chrono::seconds(1);
  while (!job_state_is_final(job_state)) {
    // Messages for up to a tenth of a second, then the keys, Ctrl-C and a poll.
    if (ws) {
      try {
        const auto deadline = Clock::now() + std::chrono::milliseconds(100);
        while (Clock::now() < deadline) {
          const auto m = ws->read(std::chrono::duration<double>(deadline - Clock::now()).count());
          if (!m) break;
          const std::string type = str_or(*m, "type");
          if (type == "status" && str_or(*m, "machine") == machine) {
            apply_status(*m);
          } else if (type == "job" && static_cast<std::int64_t>(num_or(*m, "job", 0)) == job_id) {
            apply_job(*m);
          } else if (type == "event" && str_or(*m, "machine") == machine) {
            const std::string kind = str_or(*m, "kind");
            const std::string text = str_or(*m, "text");
            if (kind == "error") {
              if (interactive) {
                panel.message("ERROR at " + text + "\n  (the job is held: space continues after it, s or Ctrl-C stops)");
              } else {
                // Nobody at a terminal can decide: stop (as a local run does).
                panel.message("ERROR at " + text + "\n  (no terminal to decide: stopping the job)");
                if (!stop_sent) {
                  stop();
                  stop_sent = true;
                }
              }
            } else if (kind == "alarm") {
              panel.message("ALARM: " + text);
            } else if (c.verbose || kind == "warning") {
              panel.message(kind + ": " + text);
            }
          } else if (type == "link" && str_or(*m, "machine") == machine) {
            panel.message("link: " + str_or(*m, "link") + (str_or(*m, "text").empty() ? "" : " (" + str_or(*m, "text") + ")"));
          } else if (type == "error") {
            panel.message("daemon: " + str_or(*m, "message", m->dump()));
          }
        }
      } catch (const std::exception& e) {
        panel.message(std::string("live status lost (") + e.what() + "); following the job by polling");
        ws.reset();
      }
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    for (auto& fn : actions.take()) fn();
    if (g_handoff_sigints > sigints_seen) {
      sigints_seen = g_handoff_sigints;
      if (sigints_seen == 1) {
        panel.message("Ctrl-C: stopping the job on the daemon (hold, wait, reset); Ctrl-C twice more ends this "
                      "program and leaves the daemon stopping it");
        stop();
        stop_sent = true;
      }
    }
    if (c.timeout_s > 0 && elapsed() > c.timeout_s && !stop_sent) {
      panel.message("time-out after " + format_duration(c.timeout_s) + ": stopping the job");
      stop();
      stop_sent = true;
    }
    // The job's state is polled too: the end of the job must not depend on
    // one WebSocket message, and without the socket this is all there is.
    if (Clock::now() - last_poll >= std::chrono::milliseconds(ws ? 1000 : 250)) {
      last_poll = Clock::now();
      call("job state", [&] { apply_job(api.get(jpath)); });
      if (!ws || !status_has_rx) call("machine state", [&] { apply_machine(api.get(mpath)); });
    }
    view.elapsed_s = elapsed();
    view.show_help = keys && keys->help_shown();
    if (keys)
      if (auto note = keys->take_note()) panel.message(*note);
    panel.update(view, view.elapsed_s);
  }
  keys.reset();
  // The final record (journal row, message) as the daemon keeps it.
  call("job state", [&] { apply_job(api.get(jpath)); });
  view.elapsed_s = elapsed();
  view.eta_s = job_state == "done" ? std::optional<double>(0.0) : std::nullopt;
  panel.finish(view);
  const long answered = static_cast<long>(num_or(last_progress, "lines_answered", 0));
  std::cout << "outcome: " << handoff_outcome_word(job_state) << " (" << (message.empty() ? job_state : message)
            << "); " << answered << " lines answered, last answered file line " << view.line << " in "
            << format_duration(view.elapsed_s) << "; daemon job #" << job_id;
  if (journal_id) std::cout << ", journal job " << *journal_id << " in the daemon's journal";
  std::cout << std::endl;
  if (job_state == "interrupted" || job_state == "failed")
    std::cerr << "the daemon keeps job #" << job_id << ": plan a resume from its last line there "
              << "(POST " << jpath << "/resume-plan, or its web page)\n";
  return job_state == "done" ? 0 : 1;
}

}  // namespace cncstream::app
