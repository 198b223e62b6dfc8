#pragma once
// Recognises the controller after the port opens: banner line -> candidate
// profile, then the profile's query ($I or M115) -> version lines that refine
// it ([FIRMWARE:grblHAL], [VER:... FluidNC ...]) and [OPT:..] sizes. Only
// plain ASCII lines are sent here: never an extended real-time byte.
//
// No banner means the board did not reset when the port opened, so it may
// still be running lines an earlier host sent (a host that died mid-job):
// their answers would be taken for answers to ours, and a character count
// that believes them overflows the controller's buffer. So before asking,
// it polls the status ('?', answered even with a full buffer) until the
// controller reports Idle (or Alarm) twice in a row with no answer between,
// ignoring every ok/error meanwhile; a controller that answers no '?' is
// asked after query_timeout_s as before.
#include <optional>
#include <utility>
#include <string>
#include <string_view>
#include <vector>

#include "cncstream/protocol/firmware_profile.hpp"

namespace cncstream::protocol {

struct IdentifyOptions {
  double banner_timeout_s = 3.0;  // boards without DTR reset print no banner
  double query_timeout_s = 2.0;
  double status_poll_s = 0.2;     // while waiting for a busy controller to finish
};

struct Identification {
  FirmwareProfile profile;
  bool recognised = false;
  std::string banner;                   // the banner line, if one came
  std::vector<std::string> query_lines; // answer to $I / M115
  std::vector<std::string> warnings;
};

class FirmwareIdentifier {
 public:
  // `profiles` must contain "grbl-1.1" (the base of the conservative fallback).
  FirmwareIdentifier(std::vector<FirmwareProfile> profiles, IdentifyOptions opt = {});

  void start(double now);
  void on_line(std::string_view line, double now);
  void tick(double now);
  std::string take_output() { return std::exchange(output_, {}); }
  // What the operator should hear now (a busy controller), not at the end.
  std::vector<std::string> take_notes() { return std::exchange(notes_, {}); }
  bool done() const { return result_.has_value(); }
  // When tick() must next run (a banner or query time-out); +infinity when none is pending.
  double next_deadline() const;
  const Identification& result() const { return *result_; }

  // Which profile's banner pattern matches `line`, if any (highest priority first).
  static const FirmwareProfile* match_banner(const std::vector<FirmwareProfile>& profiles, std::string_view line);

 private:
  enum class Phase { Idle, WaitBanner, WaitQuiet, Query, Done };
  void send_query(const std::string& query, double now);
  void poll_status(double now);
  void finish(const char* why);

  std::vector<FirmwareProfile> profiles_;
  IdentifyOptions opt_;
  Phase phase_ = Phase::Idle;
  double deadline_ = 0;
  const FirmwareProfile* candidate_ = nullptr;
  std::string banner_;
  std::vector<std::string> lines_;
  std::vector<std::string> warnings_;
  std::vector<std::string> notes_;
  std::string output_;
  // WaitQuiet: status reports seen, Idle/Alarm ones in a row, the next poll.
  bool status_seen_ = false, busy_noted_ = false, lone_ok_ = false;
  int calm_reports_ = 0;
  double next_poll_ = 0;
  std::optional<Identification> result_;
};

}  // namespace cncstream::protocol
