// Machines: list, state, settings, control, console, jogs, actions, overrides, hold, stop.
#include "cncstream/daemon/api.hpp"
#include "cncstream/daemon/body_fields.hpp"

namespace cncstream::daemon {

using nlohmann::json;

namespace {

Response accepted(const session::CommandResult& r) {
  if (!r) throw ApiError{409, "refused", r.reason};
  return Response::json(202, {{"accepted", true}});
}

}  // namespace

void Api::machine_routes() {
  router_.add("GET", "/api/v1/machines", [this](Request&, const Respond& res) {
    json list = json::array();
    for (const auto& m : machines_.all()) list.push_back(machines_.summary(*m));
    res(Response::json(200, {{"machines", list}}));
  });
  router_.add("GET", "/api/v1/machines/{m}", [this](Request& r, const Respond& res) {
    res(Response::json(200, machines_.state(machine(r))));
  });
  router_.add("GET", "/api/v1/machines/{m}/settings", [this](Request& r, const Respond& res) {
    res(Response::json(200, machines_.settings(machine(r))));
  });
  router_.add("GET", "/api/v1/machines/{m}/control", [this](Request& r, const Respond& res) {
    res(Response::json(200, machines_.control_json(machine(r), r.client_id)));
  });
  router_.add("POST", "/api/v1/machines/{m}/control", [this](Request& r, const Respond& res) {
    Machine& m = machine(r);
    const json b = parse_body(r);
    if (r.client_id.empty()) throw ApiError{428, "client_id_required", "taking control needs X-Client-Id"};
    const bool force = force_field(b);
    if (!m.control_holder.empty() && m.control_holder != r.client_id && !force) {
      // An idle holder loses it to the next asker.
      if (m.session->now() - m.control_seen <= config_.limits.control_idle_s)
        throw ApiError{409, "control_held", "client '" + m.control_holder + "' holds control of '" + m.config.name +
                                                "' (send {\"force\": true} to take it over)"};
    }
    machines_.set_control(m, r.client_id);
    res(Response::json(200, machines_.control_json(m, r.client_id)));
  });
  router_.add("DELETE", "/api/v1/machines/{m}/control", [this](Request& r, const Respond& res) {
    Machine& m = machine(r);
    if (!m.control_holder.empty() && m.control_holder != r.client_id)
      throw ApiError{409, "control_held", "only the holder ('" + m.control_holder + "') releases control"};
    machines_.set_control(m, "");
    res(Response::json(200, machines_.control_json(m, r.client_id)));
  });
  router_.add("POST", "/api/v1/machines/{m}/console", [this](Request& r, const Respond& res) {
    Machine& m = machine(r);
    const json b = parse_body(r);
    machines_.require_control(m, r.client_id);
    const std::string line = console_line(b);
    const auto result = m.session->console(line);
    if (result) {
      hub_.publish(m.config.name, WsHub::frame(dump_json(json{{"type", "console"}, {"machine", m.config.name}, {"dir", "out"},
                                                    {"text", line}, {"client", r.client_id}})));
    }
    res(accepted(result));
  });
  router_.add("POST", "/api/v1/machines/{m}/jog", [this](Request& r, const Respond& res) {
    Machine& m = machine(r);
    const json b = parse_body(r);
    machines_.require_control(m, r.client_id);
    const auto dir = jog_direction(b);
    const double dist = number_field(b, "distance", 0, 1000);
    const double feed = number_field(b, "feed", 0, 100000);
    res(accepted(m.session->jog_step(dir, dist, feed)));
  });
  router_.add("POST", "/api/v1/machines/{m}/jog/cancel", [this](Request& r, const Respond& res) {
    Machine& m = machine(r);
    m.jog_ws_client = 0;
    res(accepted(m.session->jog_release()));  // stopping is never refused, nor needs control
  });
  router_.add("POST", "/api/v1/machines/{m}/actions/{action}", [this](Request& r, const Respond& res) {
    Machine& m = machine(r);
    const json b = parse_body(r);
    const std::string& a = r.params.at(1);
    static const std::set<std::string> known = {"zero_axes", "safe_z", "go_to_work_zero", "spindle",
                                                "probe_z", "home", "unlock", "reset"};
    if (!known.count(a)) throw ApiError{400, "bad_request", "unknown action '" + a.substr(0, 40) + "'"};
    machines_.require_control(m, r.client_id);
    auto& s = *m.session;
    if (a == "zero_axes") {
      res(accepted(s.zero_axes(zero_axes_field(b))));
    } else if (a == "safe_z") {
      res(accepted(s.safe_z()));
    } else if (a == "go_to_work_zero") {
      res(accepted(s.go_to_work_zero()));
    } else if (a == "spindle") {
      res(accepted(s.spindle(on_field(b))));
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
  // The operator's answer at a tool change's prompt (docs/tool-change.md):
  // confirm goes on (the tool is mounted, Z is zeroed, the length is right),
  // decline stops the job. Probing at the prompt is actions/probe_z.
  router_.add("POST", "/api/v1/machines/{m}/tool-change/{answer}", [this](Request& r, const Respond& res) {
    Machine& m = machine(r);
    const std::string& a = r.params.at(1);
    if (a != "confirm" && a != "decline")
      throw ApiError{400, "bad_request", "unknown tool-change answer '" + a.substr(0, 40) + "' (confirm or decline)"};
    machines_.require_control(m, r.client_id);
    res(accepted(a == "confirm" ? m.session->tool_change_confirm() : m.session->tool_change_decline()));
  });
  router_.add("POST", "/api/v1/machines/{m}/realtime", [this](Request& r, const Respond& res) {
    Machine& m = machine(r);
    const json b = parse_body(r);
    const auto rt = override_command(b);
    machines_.require_control(m, r.client_id);
    res(accepted(m.session->realtime(rt)));
  });
  // Safety beats ownership: any authenticated client may hold or stop.
  router_.add("POST", "/api/v1/machines/{m}/hold", [this](Request& r, const Respond& res) {
    res(accepted(machine(r).session->hold()));
  });
  router_.add("POST", "/api/v1/machines/{m}/stop", [this](Request& r, const Respond& res) {
    res(accepted(machine(r).session->stop()));
  });
}

}  // namespace cncstream::daemon
