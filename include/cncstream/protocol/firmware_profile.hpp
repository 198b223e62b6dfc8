#pragma once
// Firmware profiles: what the streamer must know about a controller family,
// kept as data (firmware-profiles/*.toml) so a new firmware needs no code.
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace cncstream::protocol {

enum class FlowControl {
  CharacterCounting,  // GRBL family: fill the RX buffer, one `ok` per line
  SendResponse,       // Marlin: one line at a time, N<n> ... *<xor> checksums
};

// Real-time commands the host may send as single bytes outside the line stream.
enum class Realtime {
  StatusReport, CycleStart, FeedHold, SoftReset, SafetyDoor, JogCancel,
  FeedOvReset, FeedOvPlus10, FeedOvMinus10, FeedOvPlus1, FeedOvMinus1,
  RapidOvReset, RapidOvMedium, RapidOvLow,
  SpindleOvReset, SpindleOvPlus10, SpindleOvMinus10, SpindleOvPlus1, SpindleOvMinus1, SpindleStop,
  FloodToggle, MistToggle,
  Stop,                // grblHAL 0x19
  ParserStateReport,   // grblHAL 0x83
  FullStatusReport,    // grblHAL 0x87
  MpgToggle,           // grblHAL 0x8B
  ToolChangeAck,       // grblHAL 0xA3
};
// The key used in the TOML [realtime] table, e.g. "feed_ov_plus_10".
const char* realtime_key(Realtime r);
std::optional<Realtime> realtime_from_key(const std::string& key);

// One row of an error or alarm table: the firmware's meaning and our advice.
struct CodeInfo {
  int code = 0;
  std::string name;    // short name, e.g. "Undefined feed rate"
  std::string text;    // what the firmware means by it
  std::string action;  // what the operator should do
  bool reset_required = false;  // alarms: nothing is answered until a soft reset
  bool position_lost = false;   // alarms: re-home before cutting again
};

struct FirmwareProfile {
  std::string id;           // file stem, e.g. "grbl-1.1"
  std::string family;       // "grbl", "grblhal", "fluidnc", "marlin"
  std::string description;
  int priority = 0;         // identification tries higher priorities first
  FlowControl flow = FlowControl::CharacterCounting;
  std::size_t rx_buffer_size = 128;  // bytes; replaced by [OPT:...,rx] when reported
  std::size_t rx_margin = 1;         // bytes kept free (character counting)
  std::size_t line_length_limit = 80;  // after cleaning, without the newline
  int planner_blocks = 15;
  double status_poll_interval_s = 0.2;
  unsigned baud = 115200;
  // The board's USB is the controller's own (grblHAL on a Teensy, STM32,
  // RP2040): no UART between, the baud does not bound the bytes.
  bool native_usb = false;
  // Blocks a second the firmware can plan; 0: not modelled (link_model.hpp).
  double blocks_per_second = 0;
  std::vector<std::string> banner_patterns;   // ECMAScript regexes on a banner line
  std::vector<std::string> version_patterns;  // regexes on $I / M115 answer lines
  std::string identify_query;                 // "$I" or "M115"
  std::vector<std::string> startup_lines;     // sent after identification, send-response
  bool extended_realtime = true;  // may send bytes >= 0x80
  std::map<Realtime, std::uint8_t> realtime;
  std::map<int, CodeInfo> errors;
  std::map<int, CodeInfo> alarms;
  // Firmwares that report errors as text (Marlin's "Error:..."): the first
  // entry whose regex matches the text gives its meaning and advice.
  struct MessageInfo {
    std::string pattern;
    CodeInfo info;
  };
  std::vector<MessageInfo> messages;
  // Marlin: resend window and keepalive.
  int send_window = 1;
  double busy_timeout_s = 10.0;

  std::optional<std::uint8_t> realtime_byte(Realtime r) const;
  // Meaning of error:N / ALARM:N; an unknown code gets a generic entry.
  CodeInfo error_info(int code) const;
  CodeInfo alarm_info(int code) const;
  std::optional<CodeInfo> message_info(std::string_view text) const;
};

class ProfileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Loads one profile; `inherits = "<id>"` pulls in the named profile from the
// same folder first (tables merge by code, scalars are overridden).
FirmwareProfile load_firmware_profile(const std::filesystem::path& path);
// Every *.toml in `dir`, highest priority first.
std::vector<FirmwareProfile> load_firmware_profiles(const std::filesystem::path& dir);
// The profiles folder: $CNCSTREAM_PROFILES when set; else
// <program's folder>/../share/cncstream/firmware-profiles (an install); else,
// for a program run from its build folder, the source tree's
// firmware-profiles. ProfileError naming every place looked when none is a
// folder. The search itself is in profiles_dir.hpp.
std::filesystem::path default_profiles_dir();

// The conservative profile used when a controller is not recognised: GRBL 1.1
// line protocol, 128-byte buffer, 80-character lines, no extended bytes.
FirmwareProfile conservative_grbl_subset(const FirmwareProfile& grbl11);

}  // namespace cncstream::protocol
