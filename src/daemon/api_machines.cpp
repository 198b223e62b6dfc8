// Machines: list, state, settings, control, console, jogs, actions, overrides,
// hold, stop, and the routines outside a job.
#include "cncstream/daemon/api.hpp"
#include "cncstream/daemon/body_fields.hpp"
#include "cncstream/daemon/routine_bodies.hpp"
#include "cncstream/daemon/tool_change_settings.hpp"

#include <cmath>

#include "cncstream/gcode/program_extent.hpp"
#include "cncstream/protocol/outline_trace.hpp"

namespace cncstream::daemon {

using nlohmann::json;

namespace {

Response accepted(const session::CommandResult& r) {
  if (!r) throw ApiError{409, "refused", r.reason};
  return Response::json(202, {{"accepted", true}});
}

// An operator's answer in a path: true for confirm, false for decline, else 400.
bool confirms(const std::string& answer, const char* what) {
  if (answer != "confirm" && answer != "decline")
    throw ApiError{400, "bad_request",
                   cat({"unknown ", what, " answer '", answer.substr(0, 40), "' (confirm or decline)"})};
  return answer == "confirm";
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
    const bool yes = confirms(r.params.at(1), "tool-change");
    machines_.require_control(m, r.client_id);
    res(accepted(yes ? m.session->tool_change_confirm() : m.session->tool_change_decline()));
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

// The tool routines outside a job (docs/tool-change.md): measure the
// reference, change a tool, check the tool in the spindle (a broken-bit
// check), with the machine's [machine.tool_change] settings or the body's
// `tool_change` overrides. The session refuses them during a job, a jog, an
// alarm or another routine; the machine's state and the WebSocket's
// `routine` frames carry the prompt and the end.
void Api::routine_routes() {
  router_.add("POST", "/api/v1/machines/{m}/routines/{routine}", [this](Request& r, const Respond& res) {
    Machine& m = machine(r);
    const json b = parse_body(r);
    const std::string& name = r.params.at(1);
    if (name == "corner_probe" || name == "outline") {
      std::shared_ptr<protocol::MachineRoutine> routine;
      if (name == "corner_probe") {
        routine = std::make_shared<protocol::CornerProbeRoutine>(corner_probe_body(b));
      } else {
        const OutlineBody o = outline_body(b);
        const auto& j = jobs_.get(o.job);
        const auto p = jobs_.program(j);
        if (!p) throw ApiError{409, "bad_state", cat({"job ", std::to_string(o.job), " has no program yet (", j.row.state, ")"})};
        try {
          routine = std::make_shared<protocol::OutlineTraceRoutine>(protocol::outline_from_extent(
              gcode::program_extent(p->lines), o.safe_z, o.feed, cat({"job ", std::to_string(o.job)}),
              o.box ? protocol::OutlineShape::Box : protocol::OutlineShape::Hull));
        } catch (const std::invalid_argument& e) {
          throw ApiError{409, "refused", e.what()};
        }
      }
      machines_.require_control(m, r.client_id);
      res(accepted(m.session->run_routine(std::move(routine))));
      return;
    }
    protocol::ToolRoutineKind kind;
    if (name == "tool_measure") kind = protocol::ToolRoutineKind::MeasureReference;
    else if (name == "tool_change") kind = protocol::ToolRoutineKind::Change;
    else if (name == "tool_check") kind = protocol::ToolRoutineKind::CheckLength;
    else throw ApiError{400, "bad_request",
                        "unknown routine '" + name.substr(0, 40) +
                            "' (corner_probe, outline, tool_measure, tool_change, tool_check)"};
    if (!b.is_null() && !b.is_object()) throw ApiError{400, "bad_request", "expected a JSON object"};
    const auto tool_number = [&b](const char* key, double lo) {
      const double v = number_field(b, key, lo, 9999);
      if (v != std::floor(v)) throw ApiError{400, "bad_request", cat({key, ": a tool number (an integer)"})};
      return static_cast<int>(v);
    };
    const int tool = kind == protocol::ToolRoutineKind::Change ? tool_number("tool", 0) : 0;
    double tolerance = 0.1;
    if (kind == protocol::ToolRoutineKind::CheckLength && b.is_object() && b.contains("tolerance"))
      tolerance = number_field(b, "tolerance", 0, 10);
    ToolChangeSettings settings = m.config.tool_change;
    if (b.is_object() && b.contains("tool_change")) apply_tool_change_json(settings, b.at("tool_change"), "tool_change.");
    std::optional<protocol::ToolChangeConfig> cfg;
    try {
      cfg = routine_config(settings, true);
    } catch (const std::invalid_argument& e) {
      throw ApiError{409, "refused", e.what()};
    }
    if (!cfg) throw ApiError{409, "refused", "tool_change.method is pause: give plate, sensor, manual or controller"};
    machines_.require_control(m, r.client_id);
    if (b.is_object() && b.contains("in_spindle"))
      if (auto set = m.session->set_tool_in_spindle(tool_number("in_spindle", -1)); !set)
        throw ApiError{409, "refused", set.reason};
    res(accepted(m.session->run_tool_routine(*cfg, kind, tool, tolerance).result));
  });
  // The operator's answer at a routine's prompt (the tool mounted, the result right).
  router_.add("POST", "/api/v1/machines/{m}/routine/{answer}", [this](Request& r, const Respond& res) {
    Machine& m = machine(r);
    const bool yes = confirms(r.params.at(1), "routine");
    machines_.require_control(m, r.client_id);
    res(accepted(yes ? m.session->routine_confirm() : m.session->routine_decline()));
  });
}

}  // namespace cncstream::daemon
