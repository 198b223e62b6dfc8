#pragma once
// A routine the machine session runs (the tool change, corner probing, the
// outline trace): a pure state machine. What the controller answered and
// reported and what the operator said go in; lines to send (one at a time,
// each after the previous one's `ok`) and prompts come out. A subclass lists
// its steps in build(); each step queues a line, a wait for the machine to be
// idle, a prompt, or fails.
//
// Fail closed: an error answer, a probe answered without its [PRB], the
// machine in alarm or held (a feed hold or a door mid-routine: the operator
// stopped it; only a tool change inside a job waits through its job's hold
// instead), or an abort from the session (a lost link, a stop) end it; the
// session then sends nothing more of it.
#include <array>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "cncstream/geometry/vec3.hpp"
#include "cncstream/protocol/machine_actions.hpp"
#include "cncstream/protocol/status_report.hpp"

namespace cncstream::protocol {

// "[G54:1.000,2.000,-3.000]" -> {"G54", (1,2,-3)}; "[TLO:1.5]" -> {"TLO", (0,0,1.5)};
// nullopt for any other line (a [PRB] included).
std::optional<std::pair<std::string, geometry::Vec3>> parse_offset_report(std::string_view line);
// "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]" -> 0..5 for G54..G59; nullopt otherwise.
std::optional<int> parse_active_coordinate_system(std::string_view line);
// Millimetres on the wire: three decimals, no "-0.000".
std::string routine_mm(double v);

// What the operator is asked: to confirm a result, to mount a tool, to zero Z
// by hand, or whether a surprising measurement is right.
enum class PromptKind { Confirm, MountTool, ZeroManually, Question };
struct RoutinePrompt {
  PromptKind kind = PromptKind::Confirm;
  int tool = 0;  // MountTool, ZeroManually, Question: the tool it is about (0: unknown)
  std::string text;
};

class MachineRoutine {
 public:
  virtual ~MachineRoutine() = default;
  // "corner probe", "outline", "tool change": for the operator's messages.
  virtual const char* name() const = 0;

  // Whether a hold (Hold/Door in the status) ends it (the default). A tool
  // change inside a job waits through its job's hold and goes on at cycle
  // start; the session sets it for every routine it runs outside a job.
  void set_hold_ends_it(bool yes) { hold_ends_it_ = yes; }

  // Starts it: the first line or prompt is ready to take.
  void start();
  // The controller answered the last line sent (ok or error:N).
  void on_answer(bool ok, int code);
  // A pushed line: [PRB:...], [G54:...]...[TLO:...], [GC:...] (units: mm).
  void on_message(std::string_view line);
  // A status report (positions in mm).
  void on_status(const StatusReport& r);
  // The operator's answer to the current prompt.
  void confirm();
  void decline();
  // Ends it from outside (an alarm, a lost link, a stop).
  void abort(const std::string& why);

  // Out: the next line to send (at most one is outstanding) and a prompt.
  std::optional<std::string> take_line() { return std::exchange(line_out_, std::nullopt); }
  std::optional<RoutinePrompt> take_prompt() { return std::exchange(prompt_out_, std::nullopt); }
  const std::optional<RoutinePrompt>& pending_prompt() const { return prompt_; }

  bool finished() const { return done_ || !failure_.empty(); }
  bool succeeded() const { return done_ && failure_.empty(); }
  const std::string& failure() const { return failure_; }
  // What it did, for the operator (after success).
  const std::string& summary() const { return summary_; }

 protected:
  virtual void build() = 0;
  // What a failure names first ("corner probe", "tool change at line 42").
  virtual std::string context() const { return name(); }
  void add(std::function<void()> fn) { ops_.push_back(std::move(fn)); }
  // Queues a line; `probe`: a G38.x whose [PRB] must arrive before its ok;
  // `reports`: $# or $G, whose report lines are collected into offsets_/wcs_.
  void send(std::string line, bool probe = false, bool reports = false);
  void wait_idle();
  void prompt(std::string text, PromptKind kind = PromptKind::Confirm, int tool = 0);
  void fail(const std::string& why);
  void set_summary(std::string s) { summary_ = std::move(s); }

  // Filled as the controller reports them.
  std::optional<ProbeReport> probe_;                // the last probe's [PRB] (machine mm)
  std::map<std::string, geometry::Vec3> offsets_;             // the last $#: "G54".."G59", "G92", "TLO"
  std::optional<int> wcs_;                          // the last $G's active G54..G59 (0..5)
  bool inches_ = false;                             // the last $G said G20
  std::optional<StatusReport> status_;              // the last report (for travel, never a trigger)
  bool pin_active_ = false;                         // Pn:P in the last report

 private:
  enum class Wait { None, Answer, Idle, Confirm };
  void step();

  std::vector<std::function<void()>> ops_;
  std::size_t pc_ = 0;
  Wait wait_ = Wait::None;
  bool expect_probe_ = false, probe_seen_ = false, expect_reports_ = false;
  int idle_reports_ = 0;
  std::optional<std::string> line_out_;
  std::optional<RoutinePrompt> prompt_out_, prompt_;
  bool hold_ends_it_ = true;
  bool done_ = false;
  std::string failure_, summary_;
};

}  // namespace cncstream::protocol
