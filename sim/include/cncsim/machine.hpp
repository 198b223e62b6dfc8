#pragma once
// The simulated GRBL 1.1h router as an in-process object: bytes in, bytes
// out, and a virtual clock the caller advances. Deterministic: the same bytes
// and the same advance() calls give the same output. The pty front end and
// tests drive the same object.
//
//   cncsim::Machine m;                 // prints the banner
//   m.receive("G1 X10 F600\n");        // host -> firmware (real-time bytes act at once)
//   m.advance(0.5);                    // run 0.5 s of virtual time
//   std::string out = m.take_output(); // firmware -> host: "ok\r\n", "<Run|...>\r\n"
#include <cstddef>
#include <cstdint>
#include <deque>
#include <limits>
#include <filesystem>
#include <functional>
#include <atomic>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "cncsim/probe_targets.hpp"
#include "cncsim/settings.hpp"
#include "cncstream/gcode/interpreter.hpp"
#include "cncstream/gcode/line_lexer.hpp"
#include "cncstream/gcode/motion_planner.hpp"

namespace cncsim {

inline constexpr std::size_t kRxBufferSize = 128;  // GRBL RX_BUFFER_SIZE (127 usable)
inline constexpr std::size_t kPlannerBlocks = 15;
inline constexpr const char* kBanner = "Grbl 1.1h ['$' for help]";
// grblHAL's: a 1024-byte RX buffer and 35 planner blocks by default.
inline constexpr const char* kGrblHalBanner = "GrblHAL 1.1f ['$' or '$HELP' for help]";
inline constexpr std::size_t kGrblHalRxBufferSize = 1024;
// grblHAL's status codes beyond GRBL 1.1's table (its errors.h).
inline constexpr int kGrblHalToolChangePending = 40;  // motion (not a jog) in the Tool state
inline constexpr int kGrblHalHomingRequired = 46;     // $341 1-3 need the machine homed

// Which firmware the simulator answers as. GrblHal adds grblHAL's manual
// tool change ($341, the Tool state, 0xA3); everything else is GRBL 1.1h's.
enum class Firmware { Grbl11, GrblHal };
// "grbl" or "grblhal"; throws std::invalid_argument naming the text.
Firmware parse_firmware(const std::string& text);

// Tool: grblHAL only, after an M6 (its tool-change state).
enum class MachineState { Idle, Run, Hold, Jog, Alarm, Door, Check, Home, Sleep, Tool };

// Which byte of a line a wire fault hits: by its offset (0-based, real-time
// bytes not counted), the first byte equal to a letter, or the end of line
// (the line then merges with the next and keeps this line's number).
struct ByteOfLine {
  std::size_t offset = 0;
  char letter = 0;   // instead of the offset
  bool eol = false;  // instead of the offset
  static ByteOfLine at(std::size_t o) { return {o, 0, false}; }
  static ByteOfLine first(char c) { return {0, c, false}; }
  static ByteOfLine end_of_line() { return {0, 0, true}; }
};

// Faults on demand. Line numbers count the lines the firmware has received
// (1-based, every line including empty ones).
struct Faults {
  std::size_t drop_every = 0;     // drop every Nth received byte (0 = never)
  std::size_t corrupt_every = 0;  // flip a bit in every Nth received byte
  // Wire damage at one point: line -> the byte it hits. Each applies once
  // (a line without the letter is left alone).
  std::map<std::size_t, ByteOfLine> drop_byte_at;
  std::map<std::size_t, ByteOfLine> corrupt_byte_at;
  std::map<std::size_t, int> error_at;     // line -> answer error:E instead of running it
  std::map<std::size_t, int> alarm_at;     // line -> raise ALARM:A when it arrives
  std::map<std::size_t, double> stall_at;  // line -> stop answering for S seconds
  std::size_t vanish_after = 0;   // go silent (pty closes) after N answers (0 = never)
  int homing_failure = 0;         // $H fails with this ALARM (6..9), 0 = homing works
};

// Faults that took effect so far.
struct FaultsApplied {
  std::size_t dropped_bytes = 0, corrupted_bytes = 0;  // periodic and at a point
  std::size_t errors = 0, alarms = 0, stalls = 0;
  bool vanished = false;
};

// A received line carried out in full: answered ok and every planner block
// it queued run to its end. A line whose blocks an alarm, a reset or a jog
// cancel dropped did not run; an error answer or check mode runs nothing.
// `n` is the line's N word (0: none), the line number a program gives it.
struct ExecutedLine {
  std::size_t received = 0;  // 1-based, as lines_received() counts
  long n = 0;
};
using LineObserver = std::function<void(const ExecutedLine&)>;

struct MachineOptions {
  std::optional<std::filesystem::path> store_path;  // settings file ($$, G10, $N ...)
  Faults faults;
  // Where the tool is at power-on (machine coordinates): a simulator
  // restarted from a saved state, the tool left where the last one stopped.
  std::optional<cncstream::geometry::Vec3> start_position;
  bool strict = false;  // an RX overflow throws RxOverflowError
  // --speed max: whenever the firmware waits for planner room, a buffer sync
  // or a dwell, the virtual clock jumps ahead instead of waiting for advance().
  bool instant_waits = false;
  std::optional<double> probe_surface_z;  // G38.x touches this Z plane (machine coords)
  // A touch plate on the work, a fixed tool-length sensor (probe_targets.hpp).
  std::vector<ProbeFace> probe_faces;
  // Tool lengths: T number -> stick-out (mm below the spindle's reference
  // face). The tool in the spindle at power-on is `start_tool`; what cuts and
  // what trips the probe is its TIP: the spindle position less the mounted
  // tool's stick-out beyond the start tool's (a machine does not know it).
  std::map<int, double> stick_outs;
  int start_tool = 0;
  // The cutters by T number: what touches a probe target is the mounted
  // tool's cutter (its flank against a corner plate's wall), the tip as a
  // point for a tool not listed.
  std::map<int, cncstream::cam::Cutter> tool_shapes;
  // A real machine: a T word changes nothing physical; only the operator
  // mounts a tool (request_mount). Otherwise the T word mounts the tool once
  // the motion before it has run (the old simulated operator).
  bool operator_mounts_tools = false;
  // The serial link in virtual time: the host's bytes arrive one after
  // another at this rate (8-N-1: baud / 10; 115,200 baud = 11,520 bytes/s),
  // so the RX buffer and the planner fill only as fast as a real USB-serial
  // board's would. 0: every byte arrives the moment it is sent.
  double link_bytes_per_second = 0;
  // GRBL 1.1 plans 15 blocks ahead. A deeper planner is no real GRBL's: it
  // measures what a program loses to the look-ahead (tests).
  std::size_t planner_blocks = kPlannerBlocks;
  // The planner counts as starved below this many blocks (see LinkStats).
  std::size_t starved_below_blocks = 8;
  // grblHAL: its banner, $I, a 1024-byte RX buffer, `$341` and the Tool
  // state at an M6 (machine_tool_change.cpp).
  Firmware firmware = Firmware::Grbl11;
};

// Baud (8-N-1: a start bit, 8 data bits, a stop bit) to bytes per second.
inline double link_bytes_per_second_for_baud(double baud) { return baud / 10.0; }

// What the link and the planner did to the program's feed, in virtual time.
struct LinkStats {
  // The planner held fewer than starved_below_blocks blocks while the
  // firmware waited for a line still on its way (bytes on the wire or a part
  // of a line in the RX buffer): the host had lines left that had not arrived.
  double starved_seconds = 0;
  double dry_seconds = 0;  // of that, with the planner empty: the tool stopped mid-program
  // Feed moves (not rapids): their length, the time they took (including the
  // dry time after a feed move) and the time the same length takes at the
  // programmed F. Achieved against commanded feed is what the link allowed.
  double feed_mm = 0, feed_seconds = 0, commanded_seconds = 0;
  double achieved_feed() const { return feed_seconds > 0 ? feed_mm / feed_seconds * 60.0 : 0.0; }    // mm/min
  double commanded_feed() const { return commanded_seconds > 0 ? feed_mm / commanded_seconds * 60.0 : 0.0; }
  std::size_t bytes_arrived = 0;
};
// One line for the exit summary: "link 115200 baud: starved 1.234 s (planner
// below 8 blocks with a line on its way), dry 0.5 s; feed achieved 1270 of
// 3000 mm/min commanded (42.3 %) over 123.4 mm of feed moves".
std::string link_summary(const LinkStats& s, double baud, std::size_t starved_below);

class RxOverflowError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Called for every straight piece of tool motion (machine coordinates).
using MotionObserver = std::function<void(const cncstream::geometry::Vec3& from, const cncstream::geometry::Vec3& to, bool rapid)>;
// Called when a newly selected tool (T word) is in the spindle: after the
// motion queued before it has run (GRBL has no M6; the swap is physical).
using ToolObserver = std::function<void(int tool)>;

class Machine {
 public:
  explicit Machine(MachineOptions options = {});

  // Host -> firmware. Bytes arriving while the 128-byte RX buffer is full are
  // dropped and counted (strict: RxOverflowError).
  void receive(std::string_view bytes);
  // Firmware -> host: everything printed since the last call.
  std::string take_output();
  // Runs the virtual clock forward (less when a --stall-at fault begins:
  // its time is the wall clock's, see stalled()).
  void advance(double seconds);
  // Advances until no motion, wait or line is pending (or max_seconds pass).
  void run_until_idle(double max_seconds = 3600);
  double now() const { return now_; }

  // Inspection.
  MachineState state() const { return state_; }
  std::string state_name() const;  // "Idle", "Hold:0", "Door:0", ...
  std::string status_report();     // the '?' answer (advances the report counters)
  cncstream::geometry::Vec3 machine_position() const { return queue_.position(); }
  cncstream::geometry::Vec3 work_position() const { return queue_.position() - parser_.wco(); }
  // The mounted tool, how far its tip sits below where the start tool's
  // would (stick-out difference), and where the tip is (machine coords).
  int mounted_tool() const { return mounted_tool_; }
  double tip_drop() const;
  cncstream::geometry::Vec3 tip_position() const { return queue_.position() - cncstream::geometry::Vec3{0, 0, tip_drop()}; }
  bool probe_input() const { return probes_.triggered(tip_position(), probe_tool()); }
  // The mounted tool's cutter as the probe sees it (nullopt: a point).
  ProbeTool probe_tool() const;
  // The operator mounts tool T (any thread: applied before the next byte
  // is read or the clock runs). The removal switches to its cutter.
  void request_mount(int tool) { mount_request_.tool.store(tool); }
  const cncstream::gcode::ParserState& parser() const { return parser_; }
  const Settings& settings() const { return store_.settings; }
  const PersistentStore& store() const { return store_; }
  std::size_t rx_bytes_dropped() const { return rx_dropped_; }
  std::size_t rx_used() const { return rx_.size(); }
  std::size_t rx_capacity() const { return rx_capacity_; }
  // grblHAL: an M6 is in progress (the Tool state, or a jog inside it).
  bool tool_change_pending() const { return tool_change_; }
  std::size_t planner_blocks() const { return queue_.size(); }
  std::size_t lines_received() const { return lines_received_; }
  std::size_t lines_answered() const { return lines_answered_; }
  // Lines carried out in full (see ExecutedLine): what a program's line
  // count must equal when nothing was lost or repeated.
  std::size_t lines_executed() const { return lines_executed_; }
  const FaultsApplied& faults_applied() const { return applied_; }
  // The faults still to come, to schedule more between calls (never while
  // another thread serves the machine).
  Faults& faults() { return options_.faults; }
  bool vanished() const { return vanished_; }
  bool busy() const;  // motion, a pending line, unread RX bytes or bytes still on the wire
  const LinkStats& link_stats() const { return link_stats_; }
  // Changes the link's rate (bytes/s, 0: unthrottled) from now on; the bytes
  // already on the wire arrive at the old rate's times.
  void set_link_rate(double bytes_per_second) { options_.link_bytes_per_second = bytes_per_second; }
  std::size_t bytes_on_wire() const { return wire_.size(); }
  bool stalled() const;  // inside a --stall-at fault (time must pass for real)

  void set_motion_observer(MotionObserver observer) { observer_ = std::move(observer); }
  void set_tool_observer(ToolObserver observer) { tool_observer_ = std::move(observer); }
  void set_line_observer(LineObserver observer) { line_observer_ = std::move(observer); }
  // A limit switch closes: ALARM:1, motion stops dead, locked until reset.
  void inject_hard_limit();

 private:
  struct Step {
    enum Kind { Block, Sync, Delay, Pause, Emit, Apply, Homing, ProbeEnd } kind = Emit;
    cncstream::gcode::MotionBlock block;
    double seconds = 0;
    std::string text;
    std::function<void()> apply;
    bool started = false;
    double until = 0;
    bool jog = false;  // a $J= block: the machine enters Jog, not Run
    bool stall = false;  // a --stall-at fault delay
  };

  void boot(bool power_on);
  void apply_mount_request();
  void mount(int tool);
  void soft_reset();
  void emit(std::string_view line);
  void answer(int status);
  void receive_byte(unsigned char c);
  void arrive(unsigned char c);  // a byte off the wire: faults, then the RX buffer or a real-time command
  void deliver_due();            // the wire's bytes whose arrival time has come
  double next_wire_event() const;
  bool waiting_for_bytes() const;
  void realtime(unsigned char c);
  void pump();
  bool run_front_step();
  bool run_and_pop(Step& s);
  void process_line(const cncstream::gcode::CleanLine& line);
  void process_system(const std::string& line);
  void process_gcode(const std::string& line);
  void queue_actions(const cncstream::gcode::BlockResult& result);
  bool soft_limit_violated(const cncstream::geometry::Vec3& target) const;
  void raise_critical_alarm(int code);
  void raise_alarm(int code);
  void after_motion();
  void advance_motion(double dt, bool stop_after_block);
  bool motion_can_run() const;
  std::optional<double> next_timer() const;
  void wait_instantly();
  void apply_overrides();
  void persist();
  void run_startup_lines();
  std::string format_vec(const cncstream::geometry::Vec3& v) const;
  void start_homing();
  void feed_hold();
  void cycle_start();
  // grblHAL's manual tool change (machine_tool_change.cpp): an M6 word
  // taken off a line, the Tool state entered and left, what it refuses.
  bool grblhal() const { return options_.firmware == Firmware::GrblHal; }
  bool take_m6_word(std::string& text) const;
  int tool_change_mode() const;
  void enter_tool_change();
  void acknowledge_tool_change();
  bool finish_tool_change();  // false: the mode keeps the machine in Tool
  void reset_tool_change();
  MachineState after_jog_state() const { return tool_change_ ? MachineState::Tool : MachineState::Idle; }
  // Execution accounting (lines_executed): the lines between arrival and
  // their end, oldest first.
  struct PendingLine {
    std::size_t received = 0;
    long n = 0;
    std::size_t blocks_left = 0;  // planner blocks queued and not yet run
    bool answered = false;
    bool runs = true;  // false in check mode: nothing is carried out
  };
  PendingLine* pending_line(std::size_t received);
  void line_answered(bool ok);
  void blocks_completed(std::size_t n);
  void clear_planner();         // drops the planner's blocks: their lines did not run
  void forget_unanswered();     // lines that will never be answered (steps dropped)
  void complete_lines();
  bool wire_fault(std::map<std::size_t, ByteOfLine>& at, unsigned char c, bool eol);

  MachineOptions options_;
  PersistentStore store_;
  cncstream::gcode::ParserState parser_;
  cncstream::gcode::MotionQueue queue_;
  cncstream::gcode::LineAssembler assembler_;
  std::deque<char> rx_;
  std::deque<unsigned char> wire_;  // sent by the host, not yet arrived (link_bytes_per_second > 0)
  double wire_next_ = 0;            // when wire_.front() arrives
  LinkStats link_stats_;
  bool last_block_feed_ = false;    // the newest planned block is a feed move
  std::deque<Step> steps_;
  std::string out_;
  MotionObserver observer_;
  ToolObserver tool_observer_;
  LineObserver line_observer_;
  std::deque<PendingLine> pending_lines_;
  std::deque<std::size_t> planned_lines_;  // the received line of each planner block, oldest first
  std::size_t lines_executed_ = 0;
  FaultsApplied applied_;
  std::size_t arriving_line_ = 1;    // the line the next byte from the wire belongs to
  std::size_t arriving_offset_ = 0;  // and its offset in that line

  MachineState state_ = MachineState::Idle;
  double now_ = 0;
  bool critical_lock_ = false;  // ALARM 1/2: nothing but '?' and reset until 0x18
  bool jog_cancel_ = false;
  bool paused_ = false;         // M0 waiting for cycle start
  bool spindle_stop_ = false;   // 0x9E in hold
  int feed_ovr_ = 100, rapid_ovr_ = 100, spindle_ovr_ = 100;
  int wco_counter_ = 0, ovr_counter_ = 0;
  cncstream::geometry::Vec3 probe_position_{};
  ProbeTargets probes_;
  int mounted_tool_ = 0;
  // The operator's mount, from another thread; a Machine stays copyable and movable.
  struct MountRequest {
    std::atomic<int> tool{-1};
    MountRequest() = default;
    MountRequest(const MountRequest& o) : tool(o.tool.load()) {}
    MountRequest& operator=(const MountRequest& o) {
      tool.store(o.tool.load());
      return *this;
    }
  };
  MountRequest mount_request_;
  bool probe_succeeded_ = false;

  std::size_t rx_capacity_ = kRxBufferSize;
  bool homed_ = false;  // a $H succeeded since power-on
  // grblHAL's tool change: gc_state.tool_change, the input stream suspended
  // until 0xA3, the lines that arrived meanwhile (kept aside until cycle
  // start) and the tool the last M6 mounted.
  bool tool_change_ = false;
  bool tool_read_suspended_ = false;
  std::deque<char> tool_backup_;
  int current_tool_ = 0;

  std::size_t bytes_received_ = 0;
  std::size_t rx_dropped_ = 0;
  std::size_t lines_received_ = 0;
  std::size_t lines_answered_ = 0;
  bool vanished_ = false;
  bool popped_ = false;
};

// Where the work zero sits in the frame the material removal records: the
// start tool's tips (Machine::tip_position). A tool change re-zeroes Z on
// the longer tool, so the coordinate system then sits its tip drop higher;
// the job's cut written with that origin came out 7.3 mm below the design
// (`view --cut` showed every node gouged).
inline cncstream::geometry::Vec3 start_tool_work_origin(const Machine& m) {
  return m.parser().coord_system + m.parser().g92 - cncstream::geometry::Vec3{0, 0, m.tip_drop()};
}

}  // namespace cncsim
