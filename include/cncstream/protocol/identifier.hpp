#pragma once
// Recognises the controller after the port opens: banner line -> candidate
// profile, then the profile's query ($I or M115) -> version lines that refine
// it ([FIRMWARE:grblHAL], [VER:... FluidNC ...]) and [OPT:..] sizes. Only
// plain ASCII lines are sent here: never an extended real-time byte.
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
  bool done() const { return result_.has_value(); }
  // When tick() must next run (a banner or query time-out); +infinity when none is pending.
  double next_deadline() const;
  const Identification& result() const { return *result_; }

  // Which profile's banner pattern matches `line`, if any (highest priority first).
  static const FirmwareProfile* match_banner(const std::vector<FirmwareProfile>& profiles, std::string_view line);

 private:
  enum class Phase { Idle, WaitBanner, Query, Done };
  void send_query(const std::string& query, double now);
  void finish(const char* why);

  std::vector<FirmwareProfile> profiles_;
  IdentifyOptions opt_;
  Phase phase_ = Phase::Idle;
  double deadline_ = 0;
  const FirmwareProfile* candidate_ = nullptr;
  std::string banner_;
  std::vector<std::string> lines_;
  std::vector<std::string> warnings_;
  std::string output_;
  std::optional<Identification> result_;
};

}  // namespace cncstream::protocol
