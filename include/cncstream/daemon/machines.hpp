#pragma once
// The daemon's machines: one MachineSession each (with its journal
// subscriber and, for `sim`, the simulator), all on the daemon's io_context.
// Turns session events into WebSocket frames, keeps who holds control, and
// tells the job manager when a job starts, progresses and ends.
#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/thread_pool.hpp>

#include <nlohmann/json.hpp>

#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/daemon/config.hpp"
#include "cncstream/gcode/stream_link.hpp"
#include "cncstream/daemon/ws_hub.hpp"
#include "cncstream/geometry/mesh.hpp"
#include "cncstream/session/job_journal.hpp"
#include "cncstream/session/machine_session.hpp"
#include "cncstream/session/simulator_port.hpp"

namespace cncstream::daemon {

// `port = "sim"`: a simulator that can vanish and come back. Each
// (re)connection after the current simulator has ended gets a fresh one; a
// job that verifies its cut asks for a fresh one with its part as the design.
class SimMachinePort final : public session::MachinePort {
 public:
  SimMachinePort(session::SimulatorOptions base, std::size_t vanish_first_after);
  std::string path() override;
  void opened() override;
  std::string describe() override { return "the built-in simulator"; }
  // The next simulator cuts a stock and verifies it against `design` (work = machine coordinates),
  // with `cutter`, or the cutter of `tools` each T word selects.
  void set_next_design(std::optional<geometry::Mesh> design, std::optional<cam::Cutter> cutter, std::map<int, cam::Cutter> tools = {},
                       std::optional<geometry::Box3> stock = std::nullopt);
  // Hands over the current simulator (to be finished or dropped off the event loop).
  std::shared_ptr<session::SimulatorPort> retire();
  // The simulated operator mounts tool T (what the operator confirms at a tool change's prompt).
  void operator_mount(int tool);

 private:
  session::SimulatorOptions base_;
  std::size_t vanish_first_after_;
  std::shared_ptr<session::SimulatorPort> current_;
};

struct SimVerifyReport {
  bool gouged = false;
  std::optional<double> largest_gouge_mm;
  std::string text;
};

// What the job manager hears from a machine.
struct MachineJobListener {
  std::function<void(const std::string& machine, std::int64_t journal_id)> started;
  std::function<void(const std::string& machine, const protocol::JobProgress&)> progress;
  std::function<void(const std::string& machine, const std::string& state_text)> state;  // "running"/"held"
  // A status report while the machine's job runs: whether the machine holds
  // by itself (M0, a pendant, the door), and the job's last answered line.
  std::function<void(const std::string& machine, bool holds, long last_answered_line)> holding;
  std::function<void(const std::string& machine, protocol::JobOutcome, long last_line, const std::string& text)> ended;
  std::function<void(const std::string& machine, SimVerifyReport)> verified;
  std::function<void(const std::string& machine, bool ok, const std::string& why)> start_failed;
};

// The link a machine's programs stream over: its profile's, else GRBL 1.1's
// at its configured baud (the simulator's wire is paced at the same baud).
gcode::StreamLink machine_link(const MachineConfig& config);

struct Machine {
  MachineConfig config;
  std::shared_ptr<SimMachinePort> sim;
  std::unique_ptr<session::MachineSession> session;
  std::unique_ptr<session::JobJournal> journal;
  session::Subscription sub;
  std::string control_holder;  // client id, "" : none
  double control_seen = 0;     // session clock of the holder's last request
  std::uint64_t status_seq = 0;
  std::uint64_t jog_ws_client = 0;  // the WebSocket client whose continuous jog runs (0: none)
  double last_progress_push = -1;
  // A verified sim start: the job waits for the fresh simulator to be ready.
  std::optional<session::JobInput> pending_start;
  bool verifying = false;  // the running job's simulator verifies its cut
  std::optional<protocol::CodeInfo> last_alarm;  // while in alarm
  // A port absent at start (unplugged, powered off) is tried again every
  // reconnect_s: the session itself only retries a port it had open.
  std::unique_ptr<boost::asio::steady_timer> open_retry;
  int open_failures = 0;
};

class Machines {
 public:
  Machines(boost::asio::io_context& io, boost::asio::thread_pool& pool, const DaemonConfig& config, WsHub& hub,
           std::filesystem::path journal_path);
  ~Machines();
  void open_all();
  void set_listener(MachineJobListener l) { listener_ = std::move(l); }

  Machine* find(const std::string& name);
  std::vector<std::string> names() const;
  const std::vector<std::unique_ptr<Machine>>& all() const { return machines_; }

  // Starts a job's lines. `verify`: on a sim machine, cut a fresh stock
  // and check it against this design (work coordinates) with this cutter.
  // `tools`: T number -> cutter for a program of several tools.
  session::CommandResult start_job(Machine& m, session::JobInput job, std::optional<geometry::Mesh> design,
                                   std::optional<cam::Cutter> cutter, std::map<int, cam::Cutter> tools = {},
                                   std::optional<geometry::Box3> stock = std::nullopt);

  // Control: throws ApiError (428 no client id, 409 held by another / nobody holds it).
  void require_control(Machine& m, const std::string& client_id);
  nlohmann::json control_json(const Machine& m, const std::string& client_id) const;
  void set_control(Machine& m, const std::string& holder);
  void touch(const std::string& client_id);  // the holder is alive
  void client_gone(const std::string& client_id, std::uint64_t ws_client);  // its last socket closed

  nlohmann::json summary(const Machine& m) const;
  nlohmann::json state(const Machine& m) const;
  nlohmann::json settings(const Machine& m) const;
  std::string status_frame(Machine& m);
  // The tool change in progress: its line, tools, the step and what the
  // operator is asked (null when none).
  nlohmann::json tool_change(const Machine& m) const;
  // The routine running outside a job (its name and what the operator is
  // asked; null when none) and the machine's tool-length reference (null
  // when none: forgotten on a reset, an alarm, a homing or a re-zero).
  nlohmann::json routine(const Machine& m) const;
  nlohmann::json tool_reference(const Machine& m) const;

  std::function<nlohmann::json(const std::string& machine)> current_job;  // the job manager's view
  // The daemon's tool library's entry for the tool a machine's program
  // changes to (T number), as the tool change shows it (name, shape,
  // stick-out), or null when the library has none: the job manager's view.
  std::function<nlohmann::json(const std::string& machine, int tool)> library_tool;

 private:
  void on_event(Machine& m, const session::SessionEvent& e);
  void push_progress(const std::string& name, Machine& m);
  void try_open(Machine& m);
  void publish(Machine& m, nlohmann::json j);
  boost::asio::io_context& io_;
  boost::asio::thread_pool& pool_;
  const DaemonConfig& config_;
  WsHub& hub_;
  std::filesystem::path journal_path_;
  std::vector<std::unique_ptr<Machine>> machines_;
  MachineJobListener listener_;
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

nlohmann::json code_info_json(const std::optional<protocol::CodeInfo>& info);

}  // namespace cncstream::daemon
