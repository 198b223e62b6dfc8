#pragma once
// The GRBL-family engine (GRBL 1.1, grblHAL, FluidNC) for an identified
// controller: character counting, status polling, job policy (error -> hold
// and report; alarm -> stop and explain; controlled stop = hold, wait for
// Hold:0, soft reset), overrides, jogging and $C check passes.
#include <deque>
#include <optional>

#include "cncstream/protocol/character_counting.hpp"
#include "cncstream/protocol/engine.hpp"
#include "cncstream/protocol/execution_estimate.hpp"
#include "cncstream/protocol/jog.hpp"
#include "cncstream/protocol/modal_state.hpp"
#include "cncstream/protocol/response.hpp"

namespace cncstream::protocol {

struct GrblSessionOptions {
  std::optional<std::size_t> rx_margin;  // overrides the profile's margin
  JogConfig jog;
  bool poll_status = true;
};

class GrblSession final : public ProtocolEngine {
 public:
  explicit GrblSession(FirmwareProfile profile, GrblSessionOptions opt = {});

  void on_bytes(std::string_view bytes, double now) override;
  void tick(double now) override;

  void start_job(PreparedProgram program, JobMode mode, double now) override;
  void pause() override;
  void resume() override;
  void toggle_pause() override;
  void stop() override;
  void send_command(const std::string& line) override;
  std::optional<ToolChangeStop> tool_change_stop() const override;
  void tool_change_done() override;
  void abort_job(const std::string& why) override;
  void disconnected() override;

  bool realtime(Realtime r) override;
  const FirmwareProfile& profile() const override { return profile_; }
  const JobProgress& progress() const override { return progress_; }
  bool busy() const override;
  std::optional<StatusReport> status() const override { return tracker_.last(); }
  std::optional<std::array<int, 3>> overrides() const override { return tracker_.overrides(); }
  const StatusTracker& tracker() const { return tracker_; }
  const gcode::ParserState& modal() const override { return modal_; }
  BufferUse buffer() const override { return {counter_.in_flight_bytes(), profile_.rx_buffer_size, true}; }
  double next_deadline() const override;
  const CharacterCountingStream& counter() const { return counter_; }
  bool waiting_for_reset() const { return expect_reset_; }

  // Line handling, public so tests can feed single lines.
  void on_line(std::string_view line, double now);

 private:
  // Cycle start for a running job whose machine holds by itself (M0, a
  // pendant, the door); false when it does not.
  bool release_machine_hold();
  enum class CheckPhase { None, Entering, Streaming, Leaving };
  enum class Origin { File, Command, Jog, CheckToggle };

  void pump();
  void pump_jog() override;
  void on_answer(bool ok, int code, double now);
  void on_banner();
  void on_status(const StatusReport& r);
  void finish_job(JobOutcome o, const std::string& text);
  void set_job_state(JobState s, const std::string& why);
  void soft_reset();
  void maybe_complete();
  std::size_t in_flight_of(Origin o) const;
  void check_silence();

  FirmwareProfile profile_;
  GrblSessionOptions opt_;
  CharacterCountingStream counter_;
  LineSplitter splitter_;
  StatusTracker tracker_;
  gcode::ParserState modal_;
  double next_poll_ = 0;

  PreparedProgram program_;
  std::size_t next_index_ = 0;
  JobProgress progress_;
  ExecutionEstimate execution_;
  CheckPhase check_phase_ = CheckPhase::None;
  bool run_after_check_ = false;
  bool error_seen_ = false;

  std::deque<std::pair<PreparedLine, Origin>> commands_;
  std::deque<Origin> in_flight_origin_;  // parallel to counter_.in_flight()
  bool expect_reset_ = false;
  double reset_deadline_ = 0;
  double now_ = 0;
  bool tool_state_reported_ = false;
  bool stop_requested_ = false;
  std::string abort_reason_;  // abort_job(): why the job ends as an error
  bool hold_sent_ = false;
  // Every line answered: the job completes only when the controller reports
  // Idle twice in a row (its planner still runs up to 15 moves after the last ok).
  bool draining_ = false;
  int idle_reports_ = 0;
  double drain_poll_at_ = 0;
  bool mpg_owned_ = false;
  std::optional<Axes> last_mpos_;
  // A line whose end of line was lost on the wire never completes in the
  // controller, and no answer ever comes: an idle machine that leaves the
  // oldest line unanswered this long is reported (once per silence).
  double waiting_since_ = 0;  // the oldest line in flight has waited since then
  int idle_in_row_ = 0;       // status reports in a row saying Idle
  bool silence_reported_ = false;
};

}  // namespace cncstream::protocol
