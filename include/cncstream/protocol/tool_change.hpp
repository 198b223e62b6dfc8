#pragma once
// The tool-change routine, a pure MachineRoutine (protocol/machine_routine.hpp):
// what the controller answered, reported and what the operator said go in;
// lines to send (one at a time, each after the previous one's `ok`) and
// prompts come out. The machine session runs it when a job reaches a tool
// change (its lines are never forwarded) and the machine is idle with every
// line answered, and outside a job to measure the reference, change a tool or
// check the length of the tool in the spindle (ToolRoutineKind).
//
// Methods: a touch plate on the work or a fixed tool-length sensor (the
// tool in the spindle measured first as the reference unless the reference
// is still valid, then the new tool; the work offset's Z moved by the
// difference, written as an absolute G10 L2 and read back with $#), manual
// (the operator jogs, zeroes Z and confirms), or the controller's own
// (grblHAL with $341=0: the M6 goes to the controller, which enters its Tool
// state; the routine acknowledges it with 0xA3, the operator jogs and zeroes
// Z as with manual, cycle start ends it; G38.x is refused there, error:40).
//
// Motion that cannot hurt: spindle and coolant off first, every XY travel at
// a G53 safe Z, the probe input checked clear before each probe, bounded
// probe travel, a fast then a slow probe, the trigger from [PRB] (never the
// status position); the return at safe Z to the program's XY, the spindle
// back with its speed and a dwell, then Z. Anything unexpected (an error
// answer, no contact, the input active, a read-back that differs) fails: the
// caller ends the job.
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "cncstream/gcode/interpreter.hpp"
#include "cncstream/protocol/machine_routine.hpp"
#include "cncstream/protocol/status_report.hpp"

namespace cncstream::protocol {

enum class ToolChangeMethod { Plate, Sensor, Manual, Controller };
const char* to_string(ToolChangeMethod m);
// "plate", "sensor", "manual", "controller"; throws std::invalid_argument naming the text.
ToolChangeMethod parse_tool_change_method(const std::string& text);

struct ToolChangeConfig {
  ToolChangeMethod method = ToolChangeMethod::Plate;
  double safe_z = -1;  // machine Z (G53) of every XY travel
  // Where to probe: the plate's centre in WORK X,Y (it lies on the work);
  // the sensor's centre in MACHINE X,Y.
  double probe_x = 0, probe_y = 0;
  double probe_travel = 50;  // mm, the longest probe move (down from the safe Z)
  double fast_feed = 150, slow_feed = 20;  // mm/min
  double retract = 2;                       // mm up between the fast and the slow probe
  double max_length_change = 40;            // a larger difference is questioned before it is applied
  double spindle_dwell_s = 4;               // after the spindle is back on, before Z goes down
};

// The reference for length differences: the machine Z at which a tool
// triggered the plate or sensor, and the work offset's Z at that time. Valid
// until a reset, an alarm, a homing or a re-zero (the session forgets it).
struct ToolLengthReference {
  int tool = 0;
  double trigger_z = 0;  // machine mm
  double offset_z = 0;   // the active G5x's Z then
  ToolChangeMethod method = ToolChangeMethod::Plate;
  // The tool last measured against it (the one in the spindle) and its
  // trigger: what the broken-bit check compares a new measurement with.
  int measured_tool = 0;
  std::optional<double> measured_trigger_z = std::nullopt;
};

// What a tool routine does. Change: at a program's change inside a job, or
// outside one. Outside a job only: MeasureReference (the tool in the spindle,
// zeroed by the operator with the active work offset, becomes the reference)
// and CheckLength (the tool in the spindle measured again and compared with
// its recorded trigger: a broken-bit check after roughing).
enum class ToolRoutineKind { Change, MeasureReference, CheckLength };

struct ToolChangeRequest {
  long line = 0;       // file line of the change (0: outside a job)
  int from_tool = 0;   // in the spindle now (0: unknown)
  int to_tool = 0;     // to mount (0: the program does not say)
  std::string note;    // the program's words for the operator
  gcode::ParserState modal;  // after the last answered line: where and how the program goes on
  ToolRoutineKind kind = ToolRoutineKind::Change;
  // Inside a job the work offset is the modal state's and the routine returns
  // to the program (XY, spindle, Z, modal state). Outside one it reads the
  // active work offset with $G first and ends at the safe Z.
  bool in_job = true;
  double check_tolerance = 0.1;  // CheckLength: the largest difference from the recorded trigger, mm
};

using ToolChangePrompt = RoutinePrompt;

// What the journal keeps of one change.
struct ToolChangeRecord {
  long line = 0;
  int tool = 0;               // in the spindle when the routine ended
  ToolChangeMethod method = ToolChangeMethod::Plate;
  std::optional<double> offset_z;  // the work offset's Z written (G10 L2)
  bool length_known = false;  // the tool in the spindle is measured (or zeroed by the operator)
  bool skipped = false;       // the same tool: nothing done
  std::string note;           // what happened, for the operator
};

class ToolChangeRoutine final : public MachineRoutine {
 public:
  ToolChangeRoutine(ToolChangeConfig config, ToolChangeRequest request, std::optional<ToolLengthReference> reference);
  // "tool change", "tool-length measurement", "tool-length check".
  const char* name() const override;

  // The record says the length is unknown when a tool may have been changed
  // and was not measured.
  ToolChangeRecord record() const;
  // The reference after this routine (measured or kept); nullopt when none.
  const std::optional<ToolLengthReference>& reference() const { return reference_; }
  // The tool in the spindle as far as the routine knows.
  int mounted_tool() const { return mounted_; }
  const ToolChangeRequest& request() const { return req_; }
  const ToolChangeConfig& config() const { return cfg_; }
  // CheckLength: the new trigger minus the recorded one, once measured.
  const std::optional<double>& length_difference() const { return check_diff_; }

 private:
  void build() override;
  std::string context() const override;
  void add_prelude();
  void add_measure(double* trigger_out);
  void add_reference_measure();
  void add_change(const std::string& what);
  void add_controller_change(const std::string& what);
  void add_read_offset_z(std::function<void(double)> use);
  void add_check();
  void add_return();
  int wcs_index() const;
  std::optional<double> active_offset_z() const;

  ToolChangeConfig cfg_;
  ToolChangeRequest req_;
  std::optional<ToolLengthReference> reference_;
  int mounted_ = 0;
  bool mount_asked_ = false;
  bool length_known_ = false;
  bool skipped_ = false;
  std::optional<double> offset_written_;
  std::optional<double> check_diff_;
  double old_trigger_ = 0, new_trigger_ = 0;
};

}  // namespace cncstream::protocol
