#pragma once
// Marlin-style engine: send-response with line numbers and XOR checksums
// ("N<n> <line>*<xor>"), M110 N0 to reset the counter, "Resend: n" makes us
// resend from n (the "ok" that follows a resend request answers nothing),
// "echo:busy: processing" keeps a long move alive. Marlin has no real-time
// bytes: pause and stop stop feeding and let its small queue drain.
#include <deque>
#include <map>
#include <optional>

#include "cncstream/protocol/engine.hpp"
#include "cncstream/protocol/execution_estimate.hpp"
#include "cncstream/protocol/modal_state.hpp"
#include "cncstream/protocol/response.hpp"

namespace cncstream::protocol {

// XOR of every byte, as Marlin computes it over "N<n> <line>".
int marlin_checksum(std::string_view s);
// "N<n> <text>*<checksum>" (without newline).
std::string marlin_frame(long n, std::string_view text);

class MarlinSession final : public ProtocolEngine {
 public:
  explicit MarlinSession(FirmwareProfile profile);

  void on_bytes(std::string_view bytes, double now) override;
  void tick(double now) override;
  void on_line(std::string_view line, double now);

  void start_job(PreparedProgram program, JobMode mode, double now) override;
  void pause() override;
  void resume() override;
  void stop() override;
  void send_command(const std::string& line) override;
  void disconnected() override;

  // No real-time bytes: always false.
  bool realtime(Realtime r) override;
  const FirmwareProfile& profile() const override { return profile_; }
  const JobProgress& progress() const override { return progress_; }
  bool busy() const override;
  const gcode::ParserState& modal() const override { return modal_; }
  BufferUse buffer() const override {
    return {outstanding_.size(), static_cast<std::size_t>(profile_.send_window), false};
  }
  double next_deadline() const override;
  long next_line_number() const { return next_n_; }
  std::optional<int> planner_free() const { return planner_free_; }
  std::size_t resends() const { return resends_; }

 private:
  // Jogs are relative G1 moves between G91 and G90; a release sends M410
  // (quick stop), which Marlin's emergency parser acts on as the bytes arrive.
  enum class JogRole { None, Frame, Move, QuickStop };
  struct Sent {
    long n;
    PreparedLine line;
    bool file;
    JogRole jog = JogRole::None;
  };
  void pump();
  void pump_jog() override;
  void send_jog_line(std::string text, JogRole role);
  void send_numbered(PreparedLine line, bool file);
  void quick_stop();
  void on_ok(const Response& r);
  void finish_job(JobOutcome o, const std::string& text);

  FirmwareProfile profile_;
  LineSplitter splitter_;
  gcode::ParserState modal_;
  bool counter_reset_sent_ = false;
  bool counter_reset_acked_ = false;
  long next_n_ = 1;
  std::deque<Sent> outstanding_;       // sent, not yet answered, oldest first
  std::map<long, Sent> history_;       // recent lines by number, for resends
  std::deque<Sent> resend_queue_;      // lines to send again, in order
  bool swallow_next_ok_ = false;       // the ok that follows "Resend: n"
  bool quick_stop_sent_ = false;       // M410 of a stop is on its way
  std::size_t resends_ = 0;
  std::optional<int> planner_free_;

  PreparedProgram program_;
  std::size_t next_index_ = 0;
  JobProgress progress_;
  ExecutionEstimate execution_;
  std::deque<PreparedLine> commands_;
  std::deque<std::pair<std::string, JogRole>> jog_lines_;  // the lines of a jog move not sent yet
  double now_ = 0;
  double last_rx_ = 0;
  bool warned_silence_ = false;
};

}  // namespace cncstream::protocol
