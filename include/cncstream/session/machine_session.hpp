#pragma once
// One machine: the controller connection that outlives a job. A session owns
// its port, identifies the firmware, reads `$$`, polls status at the
// controller's cadence and lives across jobs and idle time, on an io_context
// the caller gives it (one thread may drive several sessions). Every front end
// (the CLI, the daemon, a pendant, the journal) is a client: it posts commands,
// which are refused with a reason when the state forbids them, and subscribes
// to events. Event-driven throughout: a timer armed for the engine's next
// deadline, no polling loop.
//
// Threading: call the session's methods on the thread running its io_context
// (from elsewhere, boost::asio::post a lambda to executor()). Subscribers are
// called on that thread.
#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cncstream/protocol/engine.hpp"
#include "cncstream/protocol/grbl_session.hpp"
#include "cncstream/protocol/grbl_settings.hpp"
#include "cncstream/protocol/identifier.hpp"
#include "cncstream/protocol/machine_actions.hpp"
#include "cncstream/protocol/machine_routine.hpp"
#include "cncstream/protocol/tool_change.hpp"
#include "cncstream/session/job_input.hpp"
#include "cncstream/session/machine_port.hpp"
#include "cncstream/session/session_events.hpp"
#include "cncstream/transport/serial_transport.hpp"

namespace cncstream::session {

struct MachineOptions {
  std::string name = "machine";
  std::shared_ptr<MachinePort> port;  // what to open (a device, or the in-process simulator)
  transport::SerialSettings serial;
  std::filesystem::path profiles_dir;
  std::optional<std::string> force_profile;  // skip identification's choice (still waits for the banner)
  protocol::IdentifyOptions identify;
  protocol::GrblSessionOptions grbl;
  // GRBL family: read `$$` after identification (rates and accelerations for
  // time estimates, $13 report units, $130-$132 travel).
  bool read_settings = true;
  double settings_timeout_s = 2.0;
  // After the port vanishes, try to open it again this often (0: stay
  // disconnected until open() is called). A job is never resumed by itself.
  double reconnect_interval_s = 0;
  // Safe Z, spindle speed and the touch plate for the machine actions.
  protocol::MachineActionSettings actions;
  // Tool changes in a job (GRBL family): intercepted and run by this
  // routine (protocol/tool_change.hpp); nullopt: M0/M6 go to the controller.
  std::optional<protocol::ToolChangeConfig> tool_change;
};

class MachineSession {
 public:
  MachineSession(boost::asio::io_context& io, MachineOptions options);
  ~MachineSession();
  MachineSession(const MachineSession&) = delete;
  MachineSession& operator=(const MachineSession&) = delete;

  boost::asio::io_context::executor_type executor() { return io_.get_executor(); }
  const std::string& name() const { return opt_.name; }

  // ---- connection --------------------------------------------------------
  // Opens the port and starts identification. Throws std::runtime_error
  // naming the port when it cannot be opened (with reconnect on, a later
  // attempt is scheduled all the same).
  void open();
  // Closes deliberately (not a disconnect). Refused while a job runs: stop it first.
  CommandResult close();

  // ---- commands (refused with a reason when the state forbids them) ------
  // Starts a program. Refused unless connected and ready, with no job, jog
  // or alarm; refused when a line cannot be sent to this controller (too
  // long, not plain ASCII), naming the line.
  CommandResult start_job(JobInput job, protocol::JobMode mode = protocol::JobMode::Run);
  CommandResult hold();
  CommandResult resume();
  CommandResult toggle_hold();  // the operator's one key: resume when holding, else hold
  CommandResult stop();         // controlled stop: hold, wait for motion to stop, reset
  CommandResult realtime(protocol::Realtime r);  // overrides and other real-time bytes
  // Jogs (protocol/jog_engine.hpp): refused during a job, in alarm, in
  // check mode or hold. At most two steps are queued (more are refused: a
  // fast-spun wheel does not keep the machine moving). A continuous jog has a
  // dead man: it runs while its holder calls jog_renew() within lease_s, and
  // silence, a release, a lost link or an alarm cancel it.
  CommandResult jog_step(const protocol::JogDirection& dir, double distance_mm, double feed_mm_min);
  CommandResult jog_start(const protocol::JogDirection& dir, double feed_mm_min, double lease_s = 0.3);
  CommandResult jog_renew();    // refused when no continuous jog is running
  CommandResult jog_release();  // always accepted: stopping is never refused
  double max_jog_feed() const;  // mm/min: the slowest of $110-$112 (GRBL's defaults before `$$`)
  // Machine actions (protocol/machine_actions.hpp), refused during a job or jog.
  CommandResult zero_axes(const std::string& axes);  // "X", "XY", "XYZ": work zero here
  CommandResult safe_z();
  CommandResult go_to_work_zero();  // safe Z first
  CommandResult spindle(bool on);   // off is never refused outside a job
  CommandResult probe_z();          // G38.2 to the touch plate; sets work Z at the touch
  CommandResult console(const std::string& line);  // an operator's line; refused during a job
  CommandResult unlock();  // $X (Marlin: M999)
  CommandResult home();    // $H (Marlin: G28)
  CommandResult reset();   // soft reset (0x18)
  // The operator's answer at a tool change's prompt.
  CommandResult tool_change_confirm();
  CommandResult tool_change_decline();
  // The tool-length reference (forgotten on a reset, an alarm, a homing or a re-zero).
  const std::optional<protocol::ToolLengthReference>& tool_reference() const { return tool_reference_; }
  // The routine the next job's tool changes run (nullopt: M0/M6 go to the
  // controller): a front end that lets each job choose (the daemon) sets it
  // before start_job. Refused while a job runs.
  CommandResult set_tool_change(std::optional<protocol::ToolChangeConfig> config);
  const std::optional<protocol::ToolChangeConfig>& tool_change_config() const { return opt_.tool_change; }
  // The change in progress (nullopt: none): its line, tools and note.
  const std::optional<protocol::ToolChangeRequest>& tool_change_request() const { return routine_request_; }

  // ---- routines outside a job (protocol/machine_routine.hpp) --------------
  // Corner probing (protocol/corner_probe.hpp), the outline trace
  // (protocol/outline_trace.hpp): the caller keeps the routine to read its
  // result after the Routine event that ends it. Refused unless ready and
  // idle of jobs, jogs, alarms and other routines (GRBL family, mm reports);
  // while one runs, jobs, jogs, actions and console lines are refused. An
  // alarm, a hold, a lost link or stop() end it; nothing more of it is sent.
  CommandResult run_routine(std::shared_ptr<protocol::MachineRoutine> routine);
  CommandResult routine_confirm();
  CommandResult routine_decline();
  bool routine_active() const { return machine_routine_ != nullptr; }
  // The routine running outside a job (nullptr: none).
  const protocol::MachineRoutine* routine() const { return machine_routine_.get(); }
  // The tool routines outside a job (protocol/tool_change.hpp), run as above
  // with this machine's reference and tool in the spindle, which they update
  // as a job's change does: MeasureReference (the tool in the spindle becomes
  // the reference), Change to `tool`, CheckLength (the broken-bit check: the
  // tool in the spindle against its measured length, `tolerance_mm`). A
  // failed check keeps the reference, so the next change is measured against
  // it and never against the broken bit. At its prompt the machine is the
  // operator's (jogs, actions, console lines; no homing), as at a job's
  // change; confirm waits for a jog to end. Returns the routine (its result is
  // read after the Routine event that ends it) or the refusal (also when it
  // failed at its start, before anything moved: nothing recorded to check).
  struct ToolRoutineStart {
    CommandResult result;
    std::shared_ptr<protocol::ToolChangeRoutine> routine;
  };
  ToolRoutineStart run_tool_routine(const protocol::ToolChangeConfig& config, protocol::ToolRoutineKind kind,
                                    int tool = 0, double tolerance_mm = 0.1);
  // The operator says which tool is in the spindle (0: unknown); another one
  // than the session thought forgets the reference. Refused during a job or routine.
  CommandResult set_tool_in_spindle(int tool);

  // ---- state -------------------------------------------------------------
  LinkState link() const { return link_; }
  bool ready() const { return link_ == LinkState::Ready; }
  bool job_active() const;
  bool in_alarm() const { return alarm_; }
  MachineSnapshot snapshot() const;
  // The last status report, positions in mm (nullopt: none yet, or not connected).
  std::optional<protocol::StatusReport> status() const;
  const protocol::ProtocolEngine* engine() const { return engine_.get(); }
  const protocol::GrblSettings& settings() const { return settings_; }
  // Seconds since the session was made: the clock of every event and snapshot.
  double now() const;
  std::size_t bytes_written() const;

  // ---- events ------------------------------------------------------------
  // Any number of subscribers; the returned handle unsubscribes when dropped.
  [[nodiscard]] Subscription subscribe(std::function<void(const SessionEvent&)> fn);

 private:
  void connect_transport();
  void on_data(std::string_view bytes);
  void on_port_closed(const std::string& reason);
  void after_identification();
  void on_settings_line(std::string_view line);
  void settings_done(const std::string& why);
  void start_engine();
  void drain();
  void arm_timer();
  void on_timer();
  void emit(SessionEvent e);
  void set_link(LinkState s, const std::string& why);
  void schedule_reconnect();
  void log(const std::string& text);
  void in_mm(protocol::StatusReport& r) const;
  CommandResult needs_engine(const char* what) const;
  CommandResult refuse_jog() const;
  CommandResult action(const char* what, const std::function<std::vector<std::string>()>& lines);
  std::optional<double> work_z() const;
  void on_probe_report(const protocol::ProbeReport& p);
  CommandResult refuse_in_alarm(const char* what) const;
  void tool_change_event(const protocol::Event& ev);
  void start_tool_change();
  void pump_tool_change();
  void end_tool_change(const std::string& why);
  void forget_tool_reference(const char* why);
  // Why the method cannot run on this controller (nullopt: it can): the
  // controller's own needs grblHAL's tool-change protocol (its profile's
  // 0xA3) with $341=0 read from `$$`.
  std::optional<std::string> controller_tool_change_refusal(const protocol::ToolChangeConfig& config) const;
  // A routine of the controller method waits in grblHAL's Tool state.
  bool in_controller_tool_state() const;
  void send_routine_realtime(protocol::MachineRoutine& r);
  bool operator_turn() const;
  // A tool routine outside a job waits for the operator: jogs, the machine
  // actions (zero Z) and console lines are accepted, as at a job's change.
  bool routine_operator_turn() const;
  CommandResult refuse_during_routine(const char* what) const;
  void machine_routine_event(const protocol::Event& ev);
  // Shared by the tool change in a job and the routines outside one: the
  // controller's answers, reports and status in, its next line out.
  static void feed_routine(protocol::MachineRoutine& r, std::string& line_in_flight, const protocol::Event& ev);
  void send_routine_line(protocol::MachineRoutine& r, std::string& line_in_flight);
  void pump_machine_routine();
  void end_machine_routine(const std::string& why);

  boost::asio::io_context& io_;
  MachineOptions opt_;
  std::chrono::steady_clock::time_point t0_;
  std::vector<protocol::FirmwareProfile> profiles_;
  LinkState link_ = LinkState::Closed;
  std::shared_ptr<transport::SerialTransport> transport_;
  std::size_t bytes_written_before_ = 0;  // by transports of earlier connections

  std::unique_ptr<protocol::FirmwareIdentifier> identifier_;
  protocol::LineSplitter id_splitter_;
  std::string pending_after_id_;
  enum class SettingsPhase { NotStarted, Reading, Done } settings_phase_ = SettingsPhase::NotStarted;
  double settings_deadline_ = 0;
  protocol::GrblSettings settings_;
  protocol::FirmwareProfile profile_;
  std::string banner_;
  std::unique_ptr<protocol::ProtocolEngine> engine_;
  bool report_inches_ = false;
  bool alarm_ = false;
  bool probe_pending_ = false;  // G38.2 sent, its [PRB:] not seen yet

  std::optional<JobInput> job_;  // the running job (its lines stay with the engine)

  std::unique_ptr<protocol::ToolChangeRoutine> routine_;
  std::optional<protocol::ToolChangeRequest> routine_request_;  // while routine_ runs
  std::string routine_line_;  // cleaned text of the routine's line in flight ("" none)
  std::optional<protocol::ToolLengthReference> tool_reference_;
  int tool_in_spindle_ = 0;

  std::shared_ptr<protocol::MachineRoutine> machine_routine_;  // outside a job
  std::shared_ptr<protocol::ToolChangeRoutine> tool_routine_;  // machine_routine_, when it is a tool routine
  std::string machine_routine_line_;  // cleaned text of its line in flight ("" none)

  boost::asio::steady_timer timer_;
  double timer_at_ = 0;
  bool timer_armed_ = false;
  boost::asio::steady_timer reconnect_timer_;

  std::shared_ptr<SubscriberList> subscribers_;
  std::shared_ptr<bool> alive_;  // handlers posted by the session check it
};

}  // namespace cncstream::session
