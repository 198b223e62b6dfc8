#pragma once
// One streaming session as the operator runs it: port (a serial device,
// `auto`, or `sim` for the built-in simulator), the live display and keys,
// the journal, and the end-of-job report. Shared by the bare form
// `cncstream FILE PORT`, `cncstream stream` and `cncstream resume`.
#include <CLI/CLI.hpp>

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/gcode/motion_planner.hpp"
#include "cncstream/gcode/stream_link.hpp"
#include "cncstream/geometry/mesh.hpp"
#include "cncstream/session/simulator_port.hpp"
#include "cncstream/session/stream_runner.hpp"
#include "job_display.hpp"

namespace cncstream::app {

struct ConnectionOptions {
  std::string port = "auto";
  std::string serial = "115200";
  std::string profile, journal;
  std::string link_rate;  // --link-rate: bytes/s, NNNbaud or usb (empty: the profile's)
  bool no_journal = false, check = false, check_only = false, verbose = false, yes = false;
  bool view = false;  // the 3-D viewer beside the job (live_view.hpp)
  double progress_interval_s = 5;  // plain progress lines without a TTY
  double timeout_s = 0;            // give up after this long (0: never)
  // Tool changes (protocol/tool_change.hpp): plate, sensor, manual, or pause
  // (the old way: the M0 goes to the controller). "" = the default: plate on
  // the simulator, manual on a real machine.
  std::string tool_change_method;
  std::optional<double> tool_change_safe_z;  // machine Z (G53)
  std::string touch_plate_at;   // work X,Y of the plate's centre
  std::string tool_sensor_at;   // machine X,Y of the sensor
  double probe_travel = 50;     // mm
  double max_length_change = 40;  // mm
};

struct SimCliOptions {
  std::string speed = "max";
  double baud = 115200;  // the simulated link (0: unthrottled)
  bool lenient = false;  // strict RX buffer is the default
  std::string settings;
  bool no_verify = false;
  std::string design, tool, png;  // verify a G-code job: design STL (machine coords) + cutter
  std::string tool_table, result;
  double resolution = 0.1, tolerance = 0.05;
  std::size_t drop_every = 0, corrupt_every = 0, vanish_after = 0;
  std::vector<std::string> error_at, alarm_at, stall_at;
  std::string touch_plate;  // X,Y,THICKNESS on the stock (machine mm); default at the tool-change plate position
  std::string tool_sensor;  // X,Y,Z (machine mm)
};

// Options after the positional FILE/JOB and PORT.
void add_connection_options(CLI::App* sub, ConnectionOptions& o);
void add_sim_options(CLI::App* sub, SimCliOptions& o);
// The parts of those that any session needs, not only a job's: the link
// (--serial, --profile, --verbose) and the simulated machine (speed, RX
// buffer, settings, faults).
void add_link_options(CLI::App* sub, ConnectionOptions& o);
// The tool-change group (--tool-change-method, --tool-change-safe-z,
// --touch-plate-at, --tool-sensor-at, --probe-travel, --max-length-change).
void add_tool_change_options(CLI::App* sub, ConnectionOptions& o);
void add_sim_machine_options(CLI::App* sub, SimCliOptions& o);

std::filesystem::path journal_path(const ConnectionOptions& o);

// PORT=sim: the simulator's speed, RX buffer, settings file and faults (the
// cut and its verify are a job's, added by run_session). Throws
// std::invalid_argument for a malformed fault.
session::SimulatorOptions simulator_options(const SimCliOptions& s);
// The device for a PORT other than `sim`: `auto` picks the one known
// controller board (saying which on stderr); nullopt, after saying why on
// stderr, when there is not exactly one.
std::optional<std::string> device_path(const std::string& port);

// The tool-change routine's settings from the options; `changes`: they are
// needed (the program changes tools, or a tool routine runs), so what is
// missing is refused naming the option. On the simulator (`so`, with its
// stock in machine = work coordinates, if any) also where its plate or sensor
// is, when not given. nullopt: the M0 goes to the controller (pause).
std::optional<protocol::ToolChangeConfig> tool_change_config(const ConnectionOptions& c, bool changes,
                                                             session::SimulatorOptions* so, std::optional<geometry::Box3> stock);

// What the simulator should verify the cut against (from an STL job).
struct VerifyTarget {
  geometry::Mesh design;  // in work = machine coordinates of the sim
  cam::Cutter cutter;
  std::map<int, cam::Cutter> tools;  // T number -> cutter, for a program of several tools (else `cutter` throughout)
  std::optional<geometry::Box3> stock;    // the job's stock block (else the design's box)
  std::optional<geometry::Vec3> work_offset;  // work = model + offset (an STL job's placement), recorded with --sim-result
};

// Motion limits for a plan shown before connecting: the simulator's settings
// for `sim`, GRBL 1.1's shipped defaults (protocol, not the simulator) otherwise (the controller's own `$$` replaces
// them once connected).
gcode::MotionLimits planning_limits(const ConnectionOptions& c, const SimCliOptions& s);
// The link the ETA streams over: the simulator's --sim-baud, else the forced
// profile's (--profile), else GRBL 1.1's at the --serial baud; --link-rate
// replaces the bytes per second.
gcode::StreamLink planning_link(const ConnectionOptions& c, const SimCliOptions& s);

// When each file line's motion ends, for the lines the job sends.
EtaEstimator estimate_job(const session::JobInput& job, const gcode::MotionLimits& limits,
                          const gcode::StreamLink& link);

// Asks "question [y/N]" on the terminal unless `yes`. Without a TTY and
// without --yes, refuses (returns false) with a message saying so.
bool confirm(const std::string& question, bool yes);

// Streams the job; prints the outcome (and the simulator's report). Returns
// the process exit code: 0 completed / check passed, 1 not completed,
// 3 the simulator's verify found a gouge, 4 the simulator's RX buffer overflowed.
int run_session(const ConnectionOptions& c, const SimCliOptions& s, const session::JobInput& job,
                std::optional<VerifyTarget> verify, std::optional<EtaEstimator> eta = std::nullopt);

}  // namespace cncstream::app
