#include "job_session.hpp"

#include <fmt/core.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>

#include "cncsim/settings.hpp"
#include "cncstream/gcode/program.hpp"
#include "cncstream/gcode/tool_change_line.hpp"
#include "cncstream/geometry/stl.hpp"
#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/protocol/link_model.hpp"
#include "cncstream/protocol/grbl_settings.hpp"
#include "cncstream/transport/journal.hpp"
#include "cncstream/transport/port_discovery.hpp"
#include "keyboard_control.hpp"
#include "live_panel.hpp"
#include "live_view.hpp"
#include "cncstream/session/simulator_port.hpp"
#include "cncsim/number_text.hpp"

namespace cncstream::app {

namespace {

std::string limits_text(const gcode::MotionLimits& m) {
  std::ostringstream o;
  o << "rates " << m.max_rate.x << "/" << m.max_rate.y << "/" << m.max_rate.z << " mm/min, accel "
    << m.acceleration.x << "/" << m.acceleration.y << "/" << m.acceleration.z << " mm/s^2";
  return o.str();
}

// "X,Y" (mm) for an option; throws naming it.
std::array<double, 2> xy_option(const std::string& text, const char* flag) {
  const auto comma = text.find(',');
  const auto x = comma == std::string::npos ? std::nullopt : cncsim::number_from<double>(text.substr(0, comma));
  const auto y = comma == std::string::npos ? std::nullopt : cncsim::number_from<double>(text.substr(comma + 1));
  if (!x || !y) throw std::invalid_argument(std::string(flag) + " '" + text + "': expected X,Y (mm)");
  return {*x, *y};
}

}  // namespace

std::optional<protocol::ToolChangeConfig> tool_change_config(const ConnectionOptions& c, bool changes,
                                                             session::SimulatorOptions* so, std::optional<geometry::Box3> stock) {
  std::string method = c.tool_change_method;
  if (method.empty()) method = so ? (stock ? "plate" : "pause") : "manual";
  if (method == "pause") return std::nullopt;
  protocol::ToolChangeConfig cfg;
  cfg.method = protocol::parse_tool_change_method(method);
  cfg.probe_travel = c.probe_travel;
  cfg.max_length_change = c.max_length_change;
  if (c.tool_change_safe_z) {
    cfg.safe_z = *c.tool_change_safe_z;
  } else if (so && stock) {
    cfg.safe_z = stock->hi.z + 40;
  } else if (changes) {
    throw std::invalid_argument("the program changes tools: give --tool-change-safe-z (the machine Z, G53, for travel "
                                "with any tool; e.g. -1 on a homed GRBL machine), or --tool-change-method pause");
  }
  if (cfg.method == protocol::ToolChangeMethod::Plate) {
    if (!c.touch_plate_at.empty()) {
      const auto p = xy_option(c.touch_plate_at, "--touch-plate-at");
      cfg.probe_x = p[0];
      cfg.probe_y = p[1];
    } else if (so && stock) {
      cfg.probe_x = stock->lo.x + 20;
      cfg.probe_y = stock->lo.y + 20;
    } else if (changes) {
      throw std::invalid_argument("--tool-change-method plate needs --touch-plate-at X,Y (work coordinates)");
    }
  }
  if (cfg.method == protocol::ToolChangeMethod::Sensor) {
    if (!c.tool_sensor_at.empty()) {
      const auto p = xy_option(c.tool_sensor_at, "--tool-sensor-at");
      cfg.probe_x = p[0];
      cfg.probe_y = p[1];
    } else if (so && stock) {
      cfg.probe_x = stock->lo.x - 30;
      cfg.probe_y = stock->lo.y;
    } else if (changes) {
      throw std::invalid_argument("--tool-change-method sensor needs --tool-sensor-at X,Y (machine coordinates)");
    }
  }
  if (so) {
    // The simulator's G54 is zero: its machine XY are the work XY.
    if (so->touch_plate.empty() && cfg.method == protocol::ToolChangeMethod::Plate && stock)
      so->touch_plate = fmt::format("{},{},5", cfg.probe_x, cfg.probe_y);
    if (so->tool_sensor.empty() && cfg.method == protocol::ToolChangeMethod::Sensor)
      so->tool_sensor = fmt::format("{},{},{}", cfg.probe_x, cfg.probe_y, stock ? stock->hi.z : 0.0);
    if (cfg.method == protocol::ToolChangeMethod::Manual && changes && !::isatty(STDIN_FILENO))
      throw std::invalid_argument("--tool-change-method manual needs an operator at a terminal (the simulated "
                                  "operator mounts and measures with plate or sensor)");
  }
  return cfg;
}

void add_link_options(CLI::App* sub, ConnectionOptions& o) {
  sub->add_option("--serial", o.serial, "Baud and frame, e.g. 115200 or 115200,8N1");
  sub->add_option("--profile", o.profile, "Force a firmware profile (grbl-1.1, grblhal, fluidnc, marlin)");
  sub->add_flag("-v,--verbose", o.verbose, "Print controller messages and status");
}

void add_connection_options(CLI::App* sub, ConnectionOptions& o) {
  add_link_options(sub, o);
  sub->add_flag("--check", o.check,
                "Run the file through check mode ($C) first; stream it only if no line has an error");
  sub->add_flag("--check-only", o.check_only, "Check mode ($C) only: report every G-code error, move nothing");
  sub->add_option("--journal", o.journal, "Journal database (default: $XDG_STATE_HOME/cncstream/journal.sqlite)");
  sub->add_flag("--no-journal", o.no_journal, "Do not journal this job");
  sub->add_flag("-y,--yes", o.yes, "Do not ask for confirmation before starting");
  sub->add_option("--progress-interval", o.progress_interval_s, "Seconds between progress lines without a terminal")
      ->check(CLI::PositiveNumber);
  sub->add_option("--timeout", o.timeout_s, "Give up after this many seconds (0: never)")->check(CLI::NonNegativeNumber);
  add_tool_change_options(sub, o);
  sub->add_flag("--view", o.view,
                "Show the job in the 3-D viewer as it runs: the cutter where the machine is, the material its moves "
                "remove (a window; closing it does not stop the job)");
}

void add_tool_change_options(CLI::App* sub, ConnectionOptions& o) {
  const char* tc = "Tool change";
  sub->add_option("--tool-change-method", o.tool_change_method,
                  "plate (touch plate on the work), sensor (fixed tool-length sensor), manual (the operator zeroes Z), "
                  "or pause (the M0 goes to the controller: no re-measure); default plate on sim, manual on a machine")
      ->check(CLI::IsMember({"plate", "sensor", "manual", "pause"}))
      ->group(tc);
  sub->add_option("--tool-change-safe-z", o.tool_change_safe_z,
                  "Machine Z (G53) for every XY travel of a tool change (needed for plate and sensor)")
      ->group(tc);
  sub->add_option("--touch-plate-at", o.touch_plate_at, "Work X,Y of the touch plate's centre (plate)")->group(tc);
  sub->add_option("--tool-sensor-at", o.tool_sensor_at, "Machine X,Y of the tool-length sensor (sensor)")->group(tc);
  sub->add_option("--probe-travel", o.probe_travel, "Longest probe move down from the safe Z, mm")
      ->check(CLI::PositiveNumber)
      ->group(tc);
  sub->add_option("--max-length-change", o.max_length_change,
                  "A tool measured this much longer or shorter than the reference is questioned, mm")
      ->check(CLI::PositiveNumber)
      ->group(tc);
}

void add_sim_machine_options(CLI::App* sub, SimCliOptions& o) {
  const char* g = "Simulator (PORT=sim)";
  sub->add_option("--sim-speed", o.speed, "Simulator time scale: 'max' or K (1 = real time)")->group(g)->capture_default_str();
  sub->add_option("--sim-baud", o.baud,
                  "Simulated serial link: bytes reach the simulator at baud/10 per virtual second, as on a USB-serial "
                  "GRBL board (0: unthrottled)")
      ->check(CLI::NonNegativeNumber)
      ->group(g)
      ->capture_default_str();
  sub->add_flag("--sim-lenient", o.lenient, "Drop overflowing RX bytes like the firmware instead of failing")->group(g);
  sub->add_option("--sim-settings", o.settings, "Simulator settings file ($$, offsets) kept across runs")->group(g);
  sub->add_option("--sim-drop-every", o.drop_every, "Fault: drop every Nth byte received")->group(g);
  sub->add_option("--sim-corrupt-every", o.corrupt_every, "Fault: flip a bit in every Nth byte received")->group(g);
  sub->add_option("--sim-error-at", o.error_at, "Fault LINE:E: answer received line LINE with error:E")->group(g);
  sub->add_option("--sim-alarm-at", o.alarm_at, "Fault LINE:A: raise ALARM:A at received line LINE")->group(g);
  sub->add_option("--sim-stall-at", o.stall_at, "Fault LINE:S: stop answering for S seconds at line LINE")->group(g);
  sub->add_option("--sim-vanish-after", o.vanish_after, "Fault: the port disappears after N answers")->group(g);
}

void add_sim_options(CLI::App* sub, SimCliOptions& o) {
  add_sim_machine_options(sub, o);
  const char* g = "Simulator (PORT=sim)";
  sub->add_flag("--no-sim-verify", o.no_verify, "Do not cut a stock and verify it (STL jobs verify by default)")->group(g);
  sub->add_option("--sim-design", o.design, "Design STL to verify a G-code job against (machine coordinates)")->group(g);
  sub->add_option("--sim-tool", o.tool, "Cutter for --sim-design, e.g. ball:3.175")->group(g);
  sub->add_option("--sim-png", o.png, "Write the verify deviation map (PNG) here")->group(g);
  sub->add_option("--sim-tool-table", o.tool_table,
                  "Tools by T number for the cut, e.g. 1=ball:3.175,2=bull:3.175:0.79 (or a file of N=SPEC lines); "
                  "SPEC@L gives each tool's stick-out (1=flat:6@30,2=ball:3.175@37.3): the simulated operator mounts "
                  "the tools and a longer one's tip cuts lower")
      ->group(g);
  sub->add_option("--sim-touch-plate", o.touch_plate,
                  "X,Y,THICKNESS: the simulator's touch plate on the stock (default: under --touch-plate-at, 5 mm)")
      ->group(g);
  sub->add_option("--sim-tool-sensor", o.tool_sensor,
                  "X,Y,Z: the simulator's tool-length sensor (default: 30 mm left of the stock, its top level with it)")
      ->group(g);
  sub->add_option("--sim-result", o.result, "Write the machined surface here (.f32 height field, and .stl)")->group(g);
  sub->add_option("--sim-resolution", o.resolution, "Stock grid step for the verify, mm")->check(CLI::PositiveNumber)->group(g);
  sub->add_option("--sim-tolerance", o.tolerance, "Verify tolerance, mm")->check(CLI::PositiveNumber)->group(g);
}

session::SimulatorOptions simulator_options(const SimCliOptions& s) {
  session::SimulatorOptions so;
  so.speed = s.speed;
  so.baud = s.baud;
  so.strict = !s.lenient;
  so.settings_file = s.settings;
  so.faults.drop_every = s.drop_every;
  so.faults.corrupt_every = s.corrupt_every;
  so.faults.vanish_after = s.vanish_after;
  so.touch_plate = s.touch_plate;
  so.tool_sensor = s.tool_sensor;
  cncsim::parse_line_faults(s.error_at, "--sim-error-at", so.faults.error_at);
  cncsim::parse_line_faults(s.alarm_at, "--sim-alarm-at", so.faults.alarm_at);
  cncsim::parse_line_faults(s.stall_at, "--sim-stall-at", so.faults.stall_at);
  return so;
}

std::optional<std::string> device_path(const std::string& port) {
  if (port != "auto") return port;
  const auto choice = transport::choose_auto_port(transport::list_ports());
  if (!choice.port) {
    std::cerr << "cncstream: error: " << choice.message << "\n";
    return std::nullopt;
  }
  std::cerr << choice.message << "\n";
  return choice.port->path;
}

std::filesystem::path journal_path(const ConnectionOptions& o) {
  return o.journal.empty() ? transport::Journal::default_path() : std::filesystem::path(o.journal);
}

gcode::MotionLimits planning_limits(const ConnectionOptions& c, const SimCliOptions& s) {
  if (c.port == "sim")
    return s.settings.empty() ? cncsim::Settings::defaults().motion_limits()
                              : cncsim::load_store(s.settings).settings.motion_limits();
  return protocol::grbl_default_motion_limits();  // refined from the controller's own $$ once connected
}

gcode::StreamLink planning_link(const ConnectionOptions& c, const SimCliOptions& s) {
  std::optional<double> rate;
  if (!c.link_rate.empty()) rate = protocol::parse_link_rate(c.link_rate);
  gcode::StreamLink link = protocol::grbl_default_link();
  if (c.port == "sim") {
    link.bytes_per_second = gcode::bytes_per_second_for_baud(s.baud);
  } else if (!c.profile.empty()) {
    link = protocol::link_model(protocol::load_firmware_profile(protocol::default_profiles_dir() / (c.profile + ".toml")));
  } else {
    link.bytes_per_second = gcode::bytes_per_second_for_baud(transport::parse_serial_settings(c.serial).baud);
  }
  if (rate) link.bytes_per_second = *rate;
  return link;
}

EtaEstimator estimate_job(const session::JobInput& job, const gcode::MotionLimits& limits,
                          const gcode::StreamLink& link) {
  std::string text;
  for (const auto& l : job.lines) text.append(l).push_back('\n');
  const auto trace = gcode::trace_program(text);
  const auto ends = gcode::estimate_line_end_times(trace, limits, job.lines.size(), link);
  std::vector<double> by_line(static_cast<std::size_t>(std::max<std::int64_t>(job.total_lines, 0)) + 1, 0.0);
  for (std::size_t i = 0; i < ends.size(); ++i) {
    const long src = job.source_lines.empty() ? long(i) + 1 : job.source_lines[i];
    if (src >= 0 && static_cast<std::size_t>(src) < by_line.size())
      by_line[static_cast<std::size_t>(src)] = std::max(by_line[static_cast<std::size_t>(src)], ends[i]);
  }
  return EtaEstimator(std::move(by_line));
}

bool confirm(const std::string& question, bool yes) {
  if (yes) return true;
  if (!::isatty(STDIN_FILENO)) {
    std::cerr << "cncstream: not starting: no terminal to confirm on; pass --yes to start without asking\n";
    return false;
  }
  std::cerr << question << " [y/N] " << std::flush;
  std::string answer;
  if (!std::getline(std::cin, answer)) return false;
  return answer == "y" || answer == "Y" || answer == "yes";
}

int run_session(const ConnectionOptions& c, const SimCliOptions& s, const session::JobInput& job,
                std::optional<VerifyTarget> verify, std::optional<EtaEstimator> precomputed) {
  std::shared_ptr<session::SimulatorPort> sim;
  session::RunnerOptions ro;
  const bool changes_tools = !gcode::find_tool_changes(job.lines).empty();
  if (c.port == "sim") {
    session::SimulatorOptions so = simulator_options(s);
    if (!s.design.empty()) {
      if (s.tool.empty()) throw std::invalid_argument("--sim-design needs --sim-tool (the cutter that cuts it)");
      verify = VerifyTarget{geometry::load_stl(s.design).mesh, cam::parse_cutter_spec(s.tool), {}, std::nullopt, std::nullopt};
    }
    if (verify && !s.no_verify) {
      so.design = verify->design;
      so.cutter = verify->cutter;
      so.stock = verify->stock;
      so.resolution = s.resolution;
      so.tolerance = s.tolerance;
      so.png = s.png;
      if (!s.tool_table.empty()) {
        so.tools = cncsim::parse_tool_table(s.tool_table);
      } else if (!verify->tools.empty()) {
        so.tools = cncsim::ToolTable(verify->tools.begin(), verify->tools.end());
      }
      so.result = s.result;
      so.work_offset = verify->work_offset;
      if (!s.tool_table.empty()) so.stick_outs = cncsim::parse_tool_stick_outs(s.tool_table);
    } else if (!s.tool_table.empty() || !s.result.empty()) {
      throw std::invalid_argument("--sim-tool-table and --sim-result need a cut to simulate: an STL job, or --sim-design "
                                  "with --sim-tool (and not --no-sim-verify)");
    }
    std::optional<geometry::Box3> stock = so.stock;
    if (!stock && so.design) stock = so.design->bounds();
    ro.tool_change = tool_change_config(c, changes_tools, &so, stock);
    sim = std::make_shared<session::SimulatorPort>(so);
    ro.machine_port = sim;
    std::cerr << "simulator: GRBL 1.1h on " << sim->path() << " (speed " << s.speed << ", "
              << (s.lenient ? "lenient" : "strict") << " RX buffer)\n";
  } else {
    const auto device = device_path(c.port);
    if (!device) return 2;
    ro.port = *device;
    ro.tool_change = tool_change_config(c, changes_tools, nullptr, std::nullopt);
  }
  ro.serial = transport::parse_serial_settings(c.serial);
  ro.profiles_dir = protocol::default_profiles_dir();
  if (!c.profile.empty()) ro.force_profile = c.profile;
  ro.mode = c.check_only ? protocol::JobMode::Check
            : c.check  ? protocol::JobMode::CheckThenRun
                       : protocol::JobMode::Run;
  if (!c.no_journal) ro.journal_path = journal_path(c);
  ro.max_run_s = c.timeout_s;

  const bool tty = ::isatty(STDERR_FILENO);
  LivePanel panel(stderr, tty, c.progress_interval_s);
  const gcode::MotionLimits default_limits = planning_limits(c, s);
  EtaEstimator eta = precomputed ? std::move(*precomputed) : estimate_job(job, default_limits, planning_link(c, s));
  std::unique_ptr<KeyboardControl> keys;

  ro.on_log = [&panel](const std::string& m) { panel.message(m); };
  ro.on_settings = [&](const protocol::GrblSettings& settings) {
    const auto limits = protocol::motion_limits_from(settings);
    if (!limits) {
      panel.message("controller settings lack $110-$112/$120-$122: ETA uses GRBL defaults");
      return;
    }
    if (limits->max_rate != default_limits.max_rate || limits->acceleration != default_limits.acceleration ||
        limits->junction_deviation != default_limits.junction_deviation)
      eta = estimate_job(job, *limits, planning_link(c, s));
    panel.message("controller settings: " + limits_text(*limits) + "; estimated machining time " +
                  format_duration(eta.total()));
  };
  const bool verbose = c.verbose;
  session::StreamRunner* runner_ptr = nullptr;
  bool interactive = false;
  ro.on_event = [&panel, verbose, &runner_ptr, &interactive](const protocol::Event& e) {
    using protocol::EventKind;
    switch (e.kind) {
      case EventKind::LineAnswered: return;
      case EventKind::Status:
        if (verbose) panel.message("status: " + e.text);
        return;
      case EventKind::Info:
      case EventKind::CommandAnswered:
        if (verbose) panel.message(e.text);
        return;
      case EventKind::LineError:
        if (interactive) {
          panel.message("ERROR at " + e.text + "\n  (the job is held: space continues after it, s or Ctrl-C stops)");
        } else {
          // Nobody at a terminal can decide: stop (hold, wait, reset).
          panel.message("ERROR at " + e.text + "\n  (no terminal to decide: stopping the job)");
          if (runner_ptr) runner_ptr->request_stop();
        }
        return;
      case EventKind::Warning:
        // A warning about one line (an idle controller that never answered
        // it): the job cannot go on by itself, and nobody at a terminal decides.
        if (e.source_line > 0 && !interactive) {
          panel.message("warning: " + e.text + "\n  (no terminal to decide: stopping the job)");
          if (runner_ptr) runner_ptr->request_stop();
          return;
        }
        panel.message(std::string("warning: ") + e.text);
        return;
      case EventKind::CheckError: panel.message("check: " + e.text); return;
      case EventKind::Alarm: panel.message("ALARM: " + e.text); return;
      default: panel.message(std::string(to_string(e.kind)) + ": " + e.text); return;
    }
  };
  const std::string title = job.file.filename().string() + " -> " + (c.port == "sim" ? std::string("sim") : ro.port);
  JobView view;
  view.title = title;
  view.total_lines = job.total_lines;
  // A program pause (M0, a tool change) holds the machine until cycle start:
  // say what the program asks of the operator, once per pause.
  long announced_pause = 0;
  auto announce_pause = [&](const session::MachineSnapshot& snap) {
    const long answered = snap.progress.last_answered_line;
    if (!snap.status || snap.status->state != protocol::MachineState::Hold ||
        snap.progress.state != protocol::JobState::Running)
      return;
    const auto pause = session::pause_at(job, answered);
    if (!pause || pause->line == announced_pause) return;
    const long line = announced_pause = pause->line;
    const std::string what = pause->note.empty() ? std::string("program pause (M0)") : pause->note;
    if (interactive) {
      panel.message("PAUSED at line " + std::to_string(line) + ": " + what + "\n  (space resumes, s or Ctrl-C stops)");
    } else if (sim) {
      // The simulator's operator mounts the tool the program selected and
      // resumes at once (the old way: nothing is measured).
      for (const auto& change : gcode::find_tool_changes(job.lines))
        if (static_cast<long>(change.index) + 1 == line && change.tool > 0) sim->operator_mount(change.tool);
      panel.message("PAUSED at line " + std::to_string(line) + ": " + what + "\n  (simulator: resuming at once)");
      runner_ptr->request_toggle_pause();
    } else {
      panel.message("PAUSED at line " + std::to_string(line) + ": " + what +
                    "\n  (no terminal: the machine stays paused until cycle start on the controller or a pendant)");
    }
  };
  // A tool change run by the session: the operator's prompts and what it did.
  ro.on_tool_change = [&](const session::SessionEvent& e) {
    if (!e.tool_prompt) {
      panel.message("tool change: " + e.text);
      return;
    }
    const auto& p = *e.tool_prompt;
    if (sim && c.yes && p.kind == protocol::PromptKind::MountTool) {
      panel.message("TOOL CHANGE: " + p.text + "\n  (simulator: the operator mounts T" + std::to_string(p.tool) +
                    " and confirms)");
      sim->operator_mount(p.tool);
      runner_ptr->request_tool_change_answer(true);
    } else if (interactive) {
      panel.message("TOOL CHANGE: " + p.text + "\n  (c confirms, x declines and stops the job)");
    } else {
      panel.message("TOOL CHANGE: " + p.text + "\n  (nobody to answer: declined, the job stops)");
      runner_ptr->request_tool_change_answer(false);
    }
  };
  // The viewer beside the job: the program, the part and the stock as it is cut.
  std::unique_ptr<LiveScene> live;
  viewer::LiveCursor cursor;
  std::unique_ptr<LiveFeed> feed;
  if (c.view) {
    live = make_live_scene(read_program_text(job.file.string()), verify ? std::optional<geometry::Mesh>(verify->design) : std::nullopt, true,
                           verify ? std::optional<cam::Cutter>(verify->cutter) : std::nullopt,
                           verify ? verify->stock : std::nullopt, s.tolerance, 0.002);
    if (live->cut) live->scene.cut = live->cut_surface();
    live->scene.progress = 0;
    panel.message("viewer: " + live->stock_text());
    feed = std::make_unique<LiveFeed>(*live, cursor);
  }
  ro.on_tick = [&](const session::MachineSnapshot& snap) {
    announce_pause(snap);
    if (feed) {
      if (snap.status && snap.status->wpos) {
        const auto& w = *snap.status->wpos;
        feed->position({w[0], w[1], w[2]});
      }
      feed->progress(segments_before_line(*live->scene.program, snap.progress.executing_line),
                     fmt::format("{} line {} of {}", protocol::to_string(snap.progress.state),
                                 snap.progress.executing_line, job.total_lines));
    }
    view.title = title + " (" + snap.profile + ")";
    view.job_state = protocol::to_string(snap.progress.state);
    view.line = snap.progress.last_answered_line;
    view.elapsed_s = snap.now;
    view.eta_s = eta.remaining(view.line, snap.now);
    if (snap.status) {
      view.machine_state = snap.status->state_text;
      view.wpos = snap.status->wpos;
      view.mpos = snap.status->mpos;
    }
    view.overrides = snap.overrides;
    if (snap.buffer.bytes && snap.buffer.capacity > 0)
      view.buffer_fill = double(snap.buffer.in_flight) / double(snap.buffer.capacity);
    view.show_help = keys && keys->help_shown();
    if (keys)
      if (auto note = keys->take_note()) panel.message(*note);
    panel.update(view, snap.now);
  };

  ro.stop_on_sigint = true;
  session::StreamRunner runner(ro);
  runner_ptr = &runner;
  session::RunResult r;
  try {
    keys = std::make_unique<KeyboardControl>(runner);  // restores the terminal when the job ends
    if (!keys->active()) keys.reset();
    interactive = keys != nullptr;
    if (feed) r = run_with_viewer(*live, cursor, *feed, title, interactive, [&] { return runner.run(job); });
    else r = runner.run(job);
    keys.reset();
  } catch (...) {
    keys.reset();
    throw;
  }
  view.job_state = to_string(r.outcome);
  view.line = r.last_answered_line;
  view.elapsed_s = r.seconds;
  view.eta_s = r.outcome == protocol::JobOutcome::Completed ? std::optional<double>(0.0) : std::nullopt;
  panel.finish(view);
  std::cout << "outcome: " << to_string(r.outcome) << " (" << r.message << "); " << r.lines_answered
            << " lines answered, last answered file line " << r.last_answered_line << ", " << r.bytes_written
            << " bytes in " << format_duration(r.seconds);
  if (r.job_id) std::cout << "; journal job " << r.job_id;
  std::cout << std::endl;
  if (r.outcome == protocol::JobOutcome::Disconnected) {
    std::cerr << "the controller went away: nothing more will be sent. Check the machine (home it, check the work "
                 "offset), then continue with: cncstream resume "
              << (r.job_id ? std::to_string(r.job_id) : std::string("JOB"))
              << " PORT (it goes back to the line the machine was last seen cutting; the controller had answered up "
                 "to line "
              << r.last_answered_line << ", but may not have run the last moves it had queued)\n";
  }
  int code = (r.outcome == protocol::JobOutcome::Completed || r.outcome == protocol::JobOutcome::CheckPassed) ? 0 : 1;
  if (sim) {
    const auto rep = sim->finish(r.outcome == protocol::JobOutcome::Completed);
    std::cout << rep.text << std::flush;
    if (rep.gouged && code == 0) code = 3;
    if (rep.overflowed) code = 4;
  }
  return code;
}

}  // namespace cncstream::app
