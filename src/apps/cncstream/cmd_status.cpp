// `cncstream status`: what the daemon's machines are doing (link, state,
// work position, job and progress, queue); with no daemon answering, says so
// and lists who holds the local serial ports (their lock files). `--json`
// prints the same as one JSON object for scripts.
#include <fmt/core.h>

#include <nlohmann/json.hpp>

#include <iostream>
#include <set>

#include "cncstream/transport/port_lock.hpp"
#include "commands.hpp"
#include "daemon_client.hpp"
#include "job_display.hpp"

namespace cncstream::app {

namespace {

using json = nlohmann::json;

// Null-safe reads (json::value() throws on a key that is present but null,
// as the API's fields are before a machine's first status report).
std::string sget(const json& j, const char* key, const std::string& fallback = "?") {
  if (!j.is_object()) return fallback;
  const auto it = j.find(key);
  return it != j.end() && it->is_string() ? it->get<std::string>() : fallback;
}
json oget(const json& j, const char* key) {
  if (!j.is_object()) return nullptr;
  const auto it = j.find(key);
  return it != j.end() ? *it : json(nullptr);
}
long long iget(const json& j, const char* key) {
  const json v = oget(j, key);
  return v.is_number() ? v.get<long long>() : 0;
}

bool status_job_unfinished(const std::string& s) {
  return s == "queued" || s == "generating" || s == "ready" || s == "running" || s == "held";
}

json owner_json(const transport::PortOwner& o) {
  json j{{"device", o.device}, {"lock_file", o.lock_file.string()}, {"pid", o.pid}, {"program", o.program},
         {"alive", o.alive}};
  j["api"] = o.api.empty() ? json(nullptr) : json(o.api);
  j["since"] = o.since ? json(static_cast<long long>(*o.since)) : json(nullptr);
  return j;
}

std::string status_pos_text(const json& a) {
  if (!a.is_array() || a.size() < 3) return "-";
  return fmt::format("{:.3f},{:.3f},{:.3f}", a[0].is_number() ? a[0].get<double>() : 0.0,
                     a[1].is_number() ? a[1].get<double>() : 0.0, a[2].is_number() ? a[2].get<double>() : 0.0);
}

std::string status_job_text(const json& jb) {
  std::string s = "#";
  s.append(std::to_string(iget(jb, "id"))).append(" ").append(sget(jb, "file_name")).append(" ").append(sget(jb, "state"));
  const json p = oget(jb, "progress");
  const json prog = oget(jb, "program");
  if (p.is_object() && p.contains("fraction") && p["fraction"].is_number()) {
    s += fmt::format(" {:.1f} %", 100.0 * p["fraction"].get<double>());
  }
  if (p.is_object() && p.contains("last_answered_line") && p["last_answered_line"].is_number()) {
    s.append(" line ").append(std::to_string(p["last_answered_line"].get<long>()));
    if (prog.is_object() && prog.contains("lines") && prog["lines"].is_number())
      s.append("/").append(std::to_string(prog["lines"].get<long>()));
  }
  if (p.is_object() && p.contains("eta_s") && p["eta_s"].is_number())
    s.append(", ETA ").append(format_duration(p["eta_s"].get<double>()));
  return s;
}

void print_owners(const std::vector<transport::PortOwner>& shown) {
  std::string dirs;
  for (const auto& d : transport::lock_dirs()) dirs.append(dirs.empty() ? "" : ", ").append(d.string());
  if (shown.empty()) {
    std::cout << "no serial port is locked (lock files in " << dirs << ")\n";
    return;
  }
  std::cout << "serial ports in use (lock files in " << dirs << "):\n";
  for (const auto& o : shown)
    std::cout << "  " << o.device << "  " << (o.alive ? "" : "stale: ") << o.describe() << "  [" << o.lock_file.string()
              << "]\n";
}

}  // namespace

void register_status(CLI::App& app, CommandRegistry& registry) {
  struct Opts {
    std::string daemon;
    bool json = false;
  };
  auto o = std::make_shared<Opts>();
  auto* sub = app.add_subcommand("status",
                                 "The daemon's machines and queues; without a daemon, who holds the local serial ports");
  sub->add_option("--daemon", o->daemon, "Daemon API address (default: $CNCSTREAM_DAEMON, the ports' lock files, "
                                         "then http://127.0.0.1:8420)");
  sub->add_flag("--json", o->json, "Print one JSON object (for scripts)");
  registry.add(sub, [o] {
    const auto owners = transport::list_port_owners();
    // Where to look: the address given, else the daemons named by live lock
    // files, else the default address (a daemon with only simulated machines
    // holds no port).
    std::vector<std::string> candidates;
    if (!o->daemon.empty()) {
      candidates.push_back(o->daemon);
    } else {
      for (const auto& ow : owners)
        if (ow.alive && !ow.api.empty() &&
            std::find(candidates.begin(), candidates.end(), ow.api) == candidates.end())
          candidates.push_back(ow.api);
      if (std::find(candidates.begin(), candidates.end(), default_daemon_address()) == candidates.end())
        candidates.push_back(default_daemon_address());
    }
    std::optional<DaemonClient> api;
    std::string version;
    std::vector<std::string> failures;
    for (const auto& cand : candidates) {
      DaemonClient client(parse_daemon_address(cand), "cncstream-status", daemon_token_from_env());
      try {
        const json health = client.get("/api/v1/health", 2);
        if (oget(health, "ok") != true) throw std::runtime_error("it answered, but not ok");
        version = sget(health, "version", "");
        api = client;
        break;
      } catch (const std::exception& e) {
        failures.push_back(client.address().url() + ": " + e.what());
      }
    }

    json out;
    out["ports"] = json::array();
    for (const auto& ow : owners) out["ports"].push_back(owner_json(ow));
    if (!api) {
      out["daemon"] = nullptr;
      out["daemon_error"] = failures.empty() ? json(nullptr) : json(failures.front());
      if (o->json) {
        std::cout << out.dump(2) << "\n";
        return 0;
      }
      std::cout << "no cncstream daemon is running";
      if (!failures.empty()) std::cout << " (" << failures.front() << ")";
      std::cout << "\n";
      print_owners(owners);
      return 0;
    }

    // The daemon's view: every machine's state, its current job, its queue.
    json daemon{{"url", api->address().url()}, {"version", version}, {"machines", json::array()}};
    std::set<std::string> daemon_devices;
    json summaries = oget(api->get("/api/v1/machines"), "machines");
    if (!summaries.is_array()) summaries = json::array();
    for (const auto& summary : summaries) {
      const std::string name = sget(summary, "name", "");
      json m = summary;
      try {
        m = api->get("/api/v1/machines/" + url_encode(name));
      } catch (const std::exception& e) {
        m["error"] = e.what();
      }
      json queue = json::array();
      try {
        json jobs = oget(api->get("/api/v1/jobs?machine=" + url_encode(name)), "jobs");
        if (!jobs.is_array()) jobs = json::array();
        for (const auto& jb : jobs)
          if (status_job_unfinished(sget(jb, "state", ""))) queue.push_back(jb);
      } catch (const std::exception& e) {
        m["queue_error"] = e.what();
      }
      m["queue"] = queue;
      daemon["machines"].push_back(m);
      if (const std::string port = sget(summary, "port", ""); port != "sim" && !port.empty())
        daemon_devices.insert(transport::resolve_device(port));
    }
    out["daemon"] = daemon;
    if (o->json) {
      std::cout << out.dump(2) << "\n";
      return 0;
    }
    std::cout << "cncstreamd at " << api->address().url() << (version.empty() ? "" : " (version " + version + ")") << ": "
              << daemon["machines"].size() << " machine" << (daemon["machines"].size() == 1 ? "" : "s") << "\n";
    for (const auto& m : daemon["machines"]) {
      const json st = oget(m, "status");
      const std::string state = st.is_object() ? sget(st, "state_text", sget(st, "state")) : sget(m, "state", "-");
      std::cout << "  " << sget(m, "name") << "  " << sget(m, "port") << "  " << sget(m, "link") << "  " << state
                << "  WPos " << (st.is_object() ? status_pos_text(oget(st, "wpos")) : std::string("-")) << "  ";
      const json* current = nullptr;
      for (const auto& jb : m["queue"])
        if (sget(jb, "state") == "running" || sget(jb, "state") == "held") current = &jb;
      std::cout << (current ? "job " + status_job_text(*current) : std::string("no job running")) << "\n";
      std::string rest;
      for (const auto& jb : m["queue"]) {
        if (&jb == current) continue;
        rest.append(rest.empty() ? "#" : ", #")
            .append(std::to_string(iget(jb, "id")))
            .append(" ")
            .append(sget(jb, "file_name"))
            .append(" (")
            .append(sget(jb, "state"))
            .append(")");
      }
      std::cout << "      queue: " << (rest.empty() ? std::string("empty") : rest) << "\n";
      if (m.contains("error")) std::cout << "      (" << m["error"].get<std::string>() << ")\n";
    }
    // Ports held by other programs than the daemon (its machines' ports, and
    // the ptys of its built-in simulators, are shown above).
    std::vector<transport::PortOwner> others;
    for (const auto& ow : owners)
      if (!daemon_devices.count(ow.device) && ow.api != api->address().url()) others.push_back(ow);
    if (!others.empty()) print_owners(others);
    return 0;
  });
}

}  // namespace cncstream::app
