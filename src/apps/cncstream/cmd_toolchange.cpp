// `cncstream toolchange measure|change T|check PORT`: the tool routines
// outside a job (protocol/tool_change.hpp), on one machine session
// (routine_session.hpp) with the tool-change options a job takes. A process
// keeps no reference after it ends (a reset or a homing in between would not
// be seen): `change` measures the tool in the spindle first, as a job's first
// change does, and `check` compares with the trigger a `measure` or `change`
// printed (--trigger). The daemon keeps the reference per machine
// (docs/api-v1.md, /routines/tool_*).
#include <fmt/core.h>

#include <iostream>
#include <memory>

#include "cncstream/protocol/tool_change.hpp"
#include "commands.hpp"
#include "routine_session.hpp"

namespace cncstream::app {

namespace detail_cmd_toolchange {

struct ToolChangeCliOptions {
  ConnectionOptions conn;
  SimCliOptions sim;
  std::vector<std::string> args;  // ACTION [T] PORT
  int in_spindle = 0;
  std::optional<double> trigger;  // check: the tool's trigger when it was measured (machine Z)
  double tolerance = 0.1;
};

int run_toolchange(ToolChangeCliOptions o) {
  const std::string action = o.args.at(0);
  protocol::ToolChangeRequest req;
  req.in_job = false;
  req.from_tool = o.in_spindle;
  req.to_tool = o.in_spindle;
  req.check_tolerance = o.tolerance;
  const bool change = action == "change";
  if (action == "measure") req.kind = protocol::ToolRoutineKind::MeasureReference;
  else if (change) req.kind = protocol::ToolRoutineKind::Change;
  else if (action == "check") req.kind = protocol::ToolRoutineKind::CheckLength;
  else throw std::invalid_argument("toolchange '" + action + "': expected measure, change T or check");
  if (o.args.size() != (change ? 3u : 2u))
    throw std::invalid_argument(change ? "toolchange change: expected change T PORT (T: the tool to mount)"
                                       : "toolchange " + action + ": expected " + action + " PORT");
  o.conn.port = o.args.back();
  if (change) {
    const std::string& t = o.args[1];
    const std::string digits = t.size() > 1 && (t[0] == 'T' || t[0] == 't') ? t.substr(1) : t;
    if (digits.empty() || digits.size() > 4 || digits.find_first_not_of("0123456789") != std::string::npos ||
        std::stoi(digits) < 1)
      throw std::invalid_argument("toolchange change '" + t + "': expected the tool to mount, e.g. 2 or T2");
    req.to_tool = std::stoi(digits);
  }
  session::SimulatorOptions so = simulator_options(o.sim);
  const bool sim = o.conn.port == "sim";
  if (sim) {
    // A bench: T1 in the spindle at power-on, the tools of the table, a
    // sensor left of machine zero (or the plate) unless told otherwise.
    so.stick_outs = session::parse_sim_stick_outs(o.sim.tool_table.empty() ? "1=flat:6@30,2=flat:6@37.3"
                                                                            : o.sim.tool_table);
    so.tool_sensor = o.sim.tool_sensor;
    so.touch_plate = o.sim.touch_plate;
    if (o.conn.tool_change_method.empty()) o.conn.tool_change_method = "sensor";
    if (!o.conn.tool_change_safe_z) o.conn.tool_change_safe_z = 30;
    if (o.conn.tool_sensor_at.empty()) o.conn.tool_sensor_at = "-30,0";
    if (o.conn.touch_plate_at.empty()) o.conn.touch_plate_at = "10,10";
    if (so.touch_plate.empty() && o.conn.tool_change_method == "plate") so.touch_plate = o.conn.touch_plate_at + ",5";
    if (req.from_tool == 0) req.from_tool = so.stick_outs.begin()->first;
    if (!change) req.to_tool = req.from_tool;
  }
  if (o.conn.tool_change_method.empty() || o.conn.tool_change_method == "pause")
    throw std::invalid_argument("toolchange: give --tool-change-method plate, sensor or manual");
  const auto cfg = tool_change_config(o.conn, true, sim ? &so : nullptr, std::nullopt);
  std::optional<protocol::ToolLengthReference> reference;
  if (req.kind == protocol::ToolRoutineKind::CheckLength) {
    if (!o.trigger)
      throw std::invalid_argument("toolchange check: give --trigger Z, the machine Z at which the tool triggered when "
                                  "it was measured (as `measure` or `change` printed it)");
    // Only the measured trigger is compared with: no offset is written.
    reference = protocol::ToolLengthReference{req.from_tool, *o.trigger, 0, cfg->method};
    reference->measured_tool = req.from_tool;
    reference->measured_trigger_z = *o.trigger;
  }
  auto routine = std::make_shared<protocol::ToolChangeRoutine>(*cfg, req, reference);
  std::cerr << fmt::format("{} ({}), T{} in the spindle{}\n", routine->name(), protocol::to_string(cfg->method),
                           req.from_tool, change ? fmt::format(", T{} to mount", req.to_tool) : std::string());
  const int code = run_machine_routine(o.conn, so, routine);
  const auto& ref = routine->reference();
  if (code == 0 && ref && ref->measured_trigger_z)
    std::cout << fmt::format("T{} triggered at machine Z{:.3f} (check it later with --trigger {:.3f})\n",
                             ref->measured_tool, *ref->measured_trigger_z, *ref->measured_trigger_z);
  return code;
}

}  // namespace detail_cmd_toolchange

void register_toolchange(CLI::App& app, CommandRegistry& registry) {
  using detail_cmd_toolchange::ToolChangeCliOptions;
  auto o = std::make_shared<ToolChangeCliOptions>();
  auto* sub = app.add_subcommand(
      "toolchange",
      "Tool routines outside a job: measure (the tool in the spindle, zeroed, becomes the reference), change T (mount "
      "T, measured against the reference; the work offset's Z follows), check (re-measure the tool in the spindle "
      "against --trigger: a broken-bit check after roughing)");
  sub->add_option("args", o->args, "measure PORT | change T PORT | check PORT")->required()->expected(2, 3);
  add_link_options(sub, o->conn);
  add_tool_change_options(sub, o->conn);
  add_sim_machine_options(sub, o->sim);
  sub->add_flag("-y,--yes", o->conn.yes, "Confirm each step without asking (the simulated operator mounts the tool)");
  sub->add_option("--timeout", o->conn.timeout_s, "Give up after this many seconds (0: never)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--in-spindle", o->in_spindle, "The tool in the spindle now (0: unknown; sim: the table's first)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--trigger", o->trigger, "check: the machine Z at which the tool triggered when it was measured");
  sub->add_option("--tolerance", o->tolerance, "check: the largest difference from --trigger, mm")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  const char* g = "Simulator (PORT=sim)";
  sub->add_option("--sim-tool-table", o->sim.tool_table,
                  "Tools and stick-outs, e.g. 1=flat:6@30,2=flat:6@37.3 (the default); the first is in the spindle")
      ->group(g);
  sub->add_option("--sim-tool-sensor", o->sim.tool_sensor, "X,Y,Z: the simulator's tool-length sensor (machine mm)")
      ->group(g);
  sub->add_option("--sim-touch-plate", o->sim.touch_plate, "X,Y,THICKNESS: the simulator's touch plate")->group(g);
  registry.add(sub, [o] { return detail_cmd_toolchange::run_toolchange(*o); });
}

}  // namespace cncstream::app
