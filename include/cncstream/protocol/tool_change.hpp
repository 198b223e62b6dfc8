#pragma once
// The tool-change routine as a pure state machine: what the controller
// answered, reported and what the operator said go in; lines to send (one at
// a time, each after the previous one's `ok`) and prompts come out. The
// machine session runs it when a job reaches a tool change (its lines are
// never forwarded) and the machine is idle with every line answered.
//
// Methods: a touch plate on the work or a fixed tool-length sensor (the
// tool in the spindle measured first as the reference unless the reference
// is still valid, then the new tool; the work offset's Z moved by the
// difference, written as an absolute G10 L2 and read back with $#), or
// manual (the operator jogs, zeroes Z and confirms).
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
#include "cncstream/protocol/status_report.hpp"

namespace cncstream::protocol {

enum class ToolChangeMethod { Plate, Sensor, Manual };
const char* to_string(ToolChangeMethod m);
// "plate", "sensor", "manual"; throws std::invalid_argument naming the text.
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
};

struct ToolChangeRequest {
  long line = 0;       // file line of the change
  int from_tool = 0;   // in the spindle now (0: unknown)
  int to_tool = 0;     // to mount (0: the program does not say)
  std::string note;    // the program's words for the operator
  gcode::ParserState modal;  // after the last answered line: where and how the program goes on
};

enum class PromptKind { MountTool, ZeroManually, Question };
struct ToolChangePrompt {
  PromptKind kind = PromptKind::MountTool;
  int tool = 0;
  std::string text;
};

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

class ToolChangeRoutine {
 public:
  ToolChangeRoutine(ToolChangeConfig config, ToolChangeRequest request, std::optional<ToolLengthReference> reference);

  // Starts it: the first line or prompt is ready to take.
  void start();
  // The controller answered the last line sent (ok or error:N).
  void on_answer(bool ok, int code);
  // A pushed line: [PRB:...], [G54:...]...[TLO:...] (units: mm).
  void on_message(std::string_view line);
  // A status report (positions in mm).
  void on_status(const StatusReport& r);
  // The operator's answer to the current prompt.
  void confirm();
  void decline();

  // Out: the next line to send (at most one is outstanding) and a prompt.
  std::optional<std::string> take_line() { return std::exchange(line_out_, std::nullopt); }
  std::optional<ToolChangePrompt> take_prompt() { return std::exchange(prompt_out_, std::nullopt); }
  const std::optional<ToolChangePrompt>& pending_prompt() const { return prompt_; }

  bool finished() const { return done_ || !failure_.empty(); }
  bool succeeded() const { return done_ && failure_.empty(); }
  const std::string& failure() const { return failure_; }
  // Ends it from outside (alarm, lost link, a stop): the record says the
  // length is unknown when a tool may have been changed.
  void abort(const std::string& why);
  ToolChangeRecord record() const;
  // The reference after this change (measured or kept); nullopt when none.
  const std::optional<ToolLengthReference>& reference() const { return reference_; }
  // The tool in the spindle as far as the routine knows.
  int mounted_tool() const { return mounted_; }

 private:
  enum class Wait { None, Answer, Idle, Confirm };
  struct Op {
    std::function<void()> run;  // queues a line, a prompt or a wait, or fails
  };
  void add(std::function<void()> fn) { ops_.push_back({std::move(fn)}); }
  void send(std::string line, bool probe = false, bool offsets = false);
  void wait_idle();
  void prompt(PromptKind kind, std::string text);
  void fail(std::string why);
  void step();
  void add_measure(double* trigger_out);
  void add_return();
  std::string wcs_p() const;

  ToolChangeConfig cfg_;
  ToolChangeRequest req_;
  std::optional<ToolLengthReference> reference_;
  std::vector<Op> ops_;
  std::size_t pc_ = 0;
  Wait wait_ = Wait::None;
  bool expect_probe_ = false, probe_seen_ = false, expect_offsets_ = false;
  int idle_reports_ = 0;
  bool pin_active_ = false;
  bool status_seen_ = false;
  std::optional<double> probe_z_;
  bool probe_touched_ = false;
  std::optional<double> offset_read_z_;
  std::optional<std::string> line_out_;
  std::optional<ToolChangePrompt> prompt_out_, prompt_;
  bool done_ = false;
  std::string failure_;
  int mounted_ = 0;
  bool mount_asked_ = false;
  bool length_known_ = false;
  bool skipped_ = false;
  std::optional<double> offset_written_;
  double old_trigger_ = 0, new_trigger_ = 0;
  std::string summary_;
};

}  // namespace cncstream::protocol
