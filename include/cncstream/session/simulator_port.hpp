#pragma once
// `PORT=sim`: the built-in simulator (cncsim's Machine behind its pty front
// end) served from a thread of this process, so a machine session talks to
// it exactly as to a USB serial port. Optionally cuts a stock block and, at
// the end, verifies the machined surface against the design. The session
// depends on the simulator here, never the other way round.
#include <atomic>
#include <exception>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "cncsim/machine.hpp"
#include "cncsim/pty_frontend.hpp"
#include "cncsim/removal.hpp"
#include "cncstream/cam/cutter.hpp"
#include "cncstream/geometry/mesh.hpp"
#include "cncstream/session/machine_port.hpp"

namespace cncstream::session {

struct SimulatorOptions {
  std::string speed = "max";  // "max" or a time scale K (1 = real time)
  double baud = 115200;       // the link's rate in virtual time (bytes/s = baud / 10); 0: unthrottled
  bool strict = true;         // an RX overflow stops the simulator (a streamer bug)
  std::string settings_file;  // persistent $$ / offsets; empty: defaults
  cncsim::Faults faults;
  // Verification: the design in machine coordinates (the sim's G54 is zero,
  // so machine = work coordinates) and the cutter that cuts it.
  std::optional<geometry::Mesh> design;
  std::optional<cam::Cutter> cutter;
  double resolution = 0.1;  // stock grid step, mm
  double tolerance = 0.05;  // verify tolerance, mm
  std::string png;          // deviation map written after the job
  std::optional<cncsim::ToolTable> tools;  // T number -> cutter (else `cutter` throughout)
  std::optional<geometry::Box3> stock;  // the block cut (machine coordinates); default: the design's box
  std::string result;       // machined surface written here (.f32 + .txt, and .stl)
  // Recorded with the result: where the part's model sits (work = model +
  // offset), so a viewer or `cncsim verify` places the design on the cut.
  std::optional<geometry::Vec3> work_offset;
  std::optional<std::filesystem::path> link;  // a stable symlink to the pty (e.g. for a reconnect test)
  std::optional<double> probe_surface_z;       // G38.x touches this Z plane (machine coordinates)
  // Tool lengths (T -> stick-out, mm; the lowest T is in the spindle at the
  // start): the machine cuts and probes with the tip, and a tool is mounted
  // only when the simulated operator mounts it (operator_mount), never by a
  // T word. A touch plate ("X,Y,THICKNESS" on the stock's top) and a fixed
  // tool-length sensor ("X,Y,Z"), machine coordinates.
  cncsim::StickOuts stick_outs;
  std::string touch_plate;
  std::string tool_sensor;
  // A corner plate ("THICKNESS,LIP[,SIZE]", cncsim --corner-plate) on the
  // stock's X-min/Y-min corner (the stock: `stock`, else the design's box).
  std::string corner_plate;
  // Where the tool is at power-on (machine mm): e.g. over the corner plate.
  std::optional<geometry::Vec3> start_position;
};

// Parses "max" or a positive number; throws std::invalid_argument naming the text.
double parse_sim_speed(const std::string& text);
// A front end's simulator settings, checked before any simulator starts
// (throw std::invalid_argument naming the text): a tool table's stick-outs
// ("1=flat:6@30,2=ball:3.175@37.3") and a tool-length sensor ("X,Y,Z").
cncsim::StickOuts parse_sim_stick_outs(const std::string& tool_table);
void check_sim_tool_sensor(const std::string& text);

class SimulatorPort final : public MachinePort {
 public:
  explicit SimulatorPort(SimulatorOptions options);
  ~SimulatorPort() override;
  SimulatorPort(const SimulatorPort&) = delete;
  SimulatorPort& operator=(const SimulatorPort&) = delete;

  // Starts serving the pty. Called once the host has opened (and flushed)
  // the port, so the power-on banner reaches the host like a DTR reset's.
  void start();
  void opened() override { start(); }
  // The pty slave to open as the serial port (the link, when one was asked for).
  std::string path() override { return path_; }
  std::string describe() override { return "the built-in simulator (" + path_ + ")"; }
  // Lines the simulated machine received and answered: read them after finish().
  std::size_t lines_received() const { return machine_->lines_received(); }
  std::size_t lines_answered() const { return machine_->lines_answered(); }
  // The controller's settings ($$), for planning before connecting.
  const cncsim::Settings& settings() const { return machine_->settings(); }
  // The simulated operator mounts tool T (thread-safe; before the host's
  // next line is read). The tool in the spindle and where its tip is.
  void operator_mount(int tool) { machine_->request_mount(tool); }
  int mounted_tool() const { return machine_->mounted_tool(); }
  // The serving thread has ended (the port vanished, overflowed, or finish()).
  bool ended() const { return ended_; }

  // Stops the simulator (after the job) and describes what it saw: lines,
  // RX overflow, material removed and, with a design, the verify result.
  // Writes the deviation PNG if one was asked for.
  struct Report {
    std::string text;
    bool overflowed = false;
    bool gouged = false;
    std::optional<double> largest_gouge_mm;  // deepest below-design node
  };
  // `let_motion_finish`: the job completed, so let the planner run out (in
  // virtual time) before the final position and the cut are read.
  Report finish(bool let_motion_finish);

 private:
  SimulatorOptions opt_;
  std::unique_ptr<cncsim::Machine> machine_;
  std::unique_ptr<cncsim::MaterialRemoval> removal_;
  std::unique_ptr<cncsim::PtyFrontEnd> front_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> ended_{false};
  std::thread thread_;
  std::string path_;
  std::string fatal_;  // what ended the simulator early (strict overflow)
  bool vanished_ = false;
  bool finished_ = false;
};

}  // namespace cncstream::session
