// Machines: list, state, settings, control, console, jogs, actions, overrides, hold, stop.
#include <cmath>

#include "cncstream/daemon/api.hpp"
#include "cncstream/protocol/firmware_profile.hpp"

namespace cncstream::daemon {

using nlohmann::json;

namespace {

Response accepted(const session::CommandResult& r) {
  if (!r) throw ApiError{409, "refused", r.reason};
  return Response::json(202, {{"accepted", true}});
}

double number_field(const json& b, const char* key, double lo, double hi) {
  if (!b.contains(key) || !b[key].is_number()) throw ApiError{400, "bad_request", std::string(key) + ": required, a number"};
  const double v = b[key].get<double>();
  if (!std::isfinite(v) || !(v > lo) || !(v <= hi))
    throw ApiError{400, "bad_request", std::string(key) + ": must be > " + std::to_string(lo) + " and <= " + std::to_string(hi)};
  return v;
}

protocol::JogDirection direction(const json& b) {
  if (!b.contains("dir") || !b["dir"].is_array() || b["dir"].size() != 3)
    throw ApiError{400, "bad_request", "dir: expected [x, y, z]"};
  protocol::JogDirection d;
  double n = 0;
  for (std::size_t i = 0; i < 3; ++i) {
    if (!b["dir"][i].is_number() || !std::isfinite(b["dir"][i].get<double>()))
      throw ApiError{400, "bad_request", "dir: expected 3 finite numbers"};
    d.v[i] = b["dir"][i].get<double>();
    n += std::abs(d.v[i]);
  }
  if (n == 0) throw ApiError{400, "bad_request", "dir: all zero"};
  return d;
}

// Overrides and coolant: the real-time bytes an operator may send here
// (hold, reset, cycle start have their own routes with their own rules).
bool override_key(const std::string& k) {
  return k.rfind("feed_ov_", 0) == 0 || k.rfind("rapid_ov_", 0) == 0 || k.rfind("spindle_ov_", 0) == 0 ||
         k == "spindle_stop" || k == "flood_toggle" || k == "mist_toggle";
}

}  // namespace

void Api::machine_routes() {
  router_.add("GET", "/api/v1/machines", [this](Request&, Respond res) {
    json list = json::array();
    for (const auto& m : machines_.all()) list.push_back(machines_.summary(*m));
    res(Response::json(200, {{"machines", list}}));
  });
  router_.add("GET", "/api/v1/machines/{m}", [this](Request& r, Respond res) {
    res(Response::json(200, machines_.state(machine(r))));
  });
  router_.add("GET", "/api/v1/machines/{m}/settings", [this](Request& r, Respond res) {
    res(Response::json(200, machines_.settings(machine(r))));
  });
  router_.add("GET", "/api/v1/machines/{m}/control", [this](Request& r, Respond res) {
    res(Response::json(200, machines_.control_json(machine(r), r.client_id)));
  });
  router_.add("POST", "/api/v1/machines/{m}/control", [this](Request& r, Respond res) {
    Machine& m = machine(r);
    const json b = parse_body(r);
    if (r.client_id.empty()) throw ApiError{428, "client_id_required", "taking control needs X-Client-Id"};
    if (b.contains("force") && !b["force"].is_boolean()) throw ApiError{400, "bad_request", "force: expected true or false"};
    const bool force = b.value("force", false);
    if (!m.control_holder.empty() && m.control_holder != r.client_id && !force) {
      // An idle holder loses it to the next asker.
      if (m.session->now() - m.control_seen <= config_.limits.control_idle_s)
        throw ApiError{409, "control_held", "client '" + m.control_holder + "' holds control of '" + m.config.name +
                                                "' (send {\"force\": true} to take it over)"};
    }
    machines_.set_control(m, r.client_id);
    res(Response::json(200, machines_.control_json(m, r.client_id)));
  });
  router_.add("DELETE", "/api/v1/machines/{m}/control", [this](Request& r, Respond res) {
    Machine& m = machine(r);
    if (!m.control_holder.empty() && m.control_holder != r.client_id)
      throw ApiError{409, "control_held", "only the holder ('" + m.control_holder + "') releases control"};
    machines_.set_control(m, "");
    res(Response::json(200, machines_.control_json(m, r.client_id)));
  });
  router_.add("POST", "/api/v1/machines/{m}/console", [this](Request& r, Respond res) {
    Machine& m = machine(r);
    const json b = parse_body(r);
    machines_.require_control(m, r.client_id);
    if (!b.contains("line") || !b["line"].is_string()) throw ApiError{400, "bad_request", "line: required, a string"};
    const std::string line = b["line"].get<std::string>();
    if (line.empty() || line.size() > 256) throw ApiError{400, "bad_request", "line: 1 to 256 characters"};
    for (std::size_t i = 0; i < line.size(); ++i) {
      const auto c = static_cast<unsigned char>(line[i]);
      if (c < 0x20 || c > 0x7e)
        throw ApiError{400, "bad_request", "line: byte " + std::to_string(i) + " is not printable ASCII (real-time bytes have their own routes)"};
    }
    const auto result = m.session->console(line);
    if (result) {
      hub_.publish(m.config.name, WsHub::frame(json{{"type", "console"}, {"machine", m.config.name}, {"dir", "out"},
                                                    {"text", line}, {"client", r.client_id}}.dump()));
    }
    res(accepted(result));
  });
  router_.add("POST", "/api/v1/machines/{m}/jog", [this](Request& r, Respond res) {
    Machine& m = machine(r);
    const json b = parse_body(r);
    machines_.require_control(m, r.client_id);
    const auto dir = direction(b);
    const double dist = number_field(b, "distance", 0, 1000);
    const double feed = number_field(b, "feed", 0, 100000);
    res(accepted(m.session->jog_step(dir, dist, feed)));
  });
  router_.add("POST", "/api/v1/machines/{m}/jog/cancel", [this](Request& r, Respond res) {
    Machine& m = machine(r);
    m.jog_ws_client = 0;
    res(accepted(m.session->jog_release()));  // stopping is never refused, nor needs control
  });
  router_.add("POST", "/api/v1/machines/{m}/actions/{action}", [this](Request& r, Respond res) {
    Machine& m = machine(r);
    const json b = parse_body(r);
    const std::string& a = r.params.at(1);
    static const std::set<std::string> known = {"zero_axes", "safe_z", "go_to_work_zero", "spindle",
                                                "probe_z", "home", "unlock", "reset"};
    if (!known.count(a)) throw ApiError{400, "bad_request", "unknown action '" + a.substr(0, 40) + "'"};
    machines_.require_control(m, r.client_id);
    auto& s = *m.session;
    if (a == "zero_axes") {
      if (!b.contains("axes") || !b["axes"].is_string()) throw ApiError{400, "bad_request", "axes: required, e.g. \"XY\""};
      const std::string axes = b["axes"].get<std::string>();
      if (axes.empty() || axes.size() > 3 || axes.find_first_not_of("XYZ") != std::string::npos)
        throw ApiError{400, "bad_request", "axes: letters from X, Y, Z"};
      res(accepted(s.zero_axes(axes)));
    } else if (a == "safe_z") {
      res(accepted(s.safe_z()));
    } else if (a == "go_to_work_zero") {
      res(accepted(s.go_to_work_zero()));
    } else if (a == "spindle") {
      if (!b.contains("on") || !b["on"].is_boolean()) throw ApiError{400, "bad_request", "on: required, true or false"};
      res(accepted(s.spindle(b["on"].get<bool>())));
    } else if (a == "probe_z") {
      res(accepted(s.probe_z()));
    } else if (a == "home") {
      res(accepted(s.home()));
    } else if (a == "unlock") {
      res(accepted(s.unlock()));
    } else {
      res(accepted(s.reset()));
    }
  });
  router_.add("POST", "/api/v1/machines/{m}/realtime", [this](Request& r, Respond res) {
    Machine& m = machine(r);
    const json b = parse_body(r);
    if (!b.contains("command") || !b["command"].is_string()) throw ApiError{400, "bad_request", "command: required"};
    const std::string k = b["command"].get<std::string>();
    const auto rt = protocol::realtime_from_key(k);
    if (!rt || !override_key(k)) throw ApiError{400, "bad_request", "command: '" + k.substr(0, 40) + "' is not an override"};
    machines_.require_control(m, r.client_id);
    res(accepted(m.session->realtime(*rt)));
  });
  // Safety beats ownership: any authenticated client may hold or stop.
  router_.add("POST", "/api/v1/machines/{m}/hold", [this](Request& r, Respond res) {
    res(accepted(machine(r).session->hold()));
  });
  router_.add("POST", "/api/v1/machines/{m}/stop", [this](Request& r, Respond res) {
    res(accepted(machine(r).session->stop()));
  });
}

}  // namespace cncstream::daemon
