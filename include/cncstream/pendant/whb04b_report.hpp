#pragma once
// The XHC WHB04B-4/-6 wireless pendant's input reports: 8 bytes from
// interrupt endpoint 0x81 of its USB receiver, decoded without any I/O, and a
// tracker that turns successive reports into what the operator did (a key
// went down or up, a knob turned, the wheel moved, the pendant slept or woke).
//
// Layout (reverse-engineered by the LinuxCNC xhc-whb04b-6 authors; the
// manufacturer publishes none):
//   [0] report id 0x04   [1] changes with every report (unused)
//   [2] key 1  [3] key 2 (two keys may be down; Fn + key is a macro)
//   [4] feed/step knob   [5] axis knob   [6] wheel detents (int8)
//   [7] checksum (nobody knows how to validate it: ignored)
// Before sleeping the pendant sends a report with every key, knob and wheel
// byte zero, then `04 ff ff ff ff ff 81 ff`; its next ordinary report means
// it woke up.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace cncstream::pendant {

using InputReport = std::array<std::uint8_t, 8>;

enum class Key : std::uint8_t {
  None = 0x00,
  Reset = 0x01,
  Stop = 0x02,
  StartPause = 0x03,
  FeedPlus = 0x04,
  FeedMinus = 0x05,
  SpindlePlus = 0x06,
  SpindleMinus = 0x07,
  MachineHome = 0x08,
  SafeZ = 0x09,
  WorkHome = 0x0A,
  SpindleOnOff = 0x0B,
  Fn = 0x0C,
  ProbeZ = 0x0D,
  Continuous = 0x0E,  // printed "MPG" on the -6
  Step = 0x0F,
  Macro10 = 0x10,
};
const char* to_string(Key k);

// The macro a key makes with Fn held, as printed on the pendant (Fn + Feed+
// is macro 1 ... Fn + Probe-Z is macro 9) and extended by LinuxCNC (Fn +
// Reset 11, Stop 12, Start/Pause 13, Macro-10 14, MPG 15, Step 16). The
// Macro-10 key alone is macro 10. 0 for None and Fn.
int fn_macro_number(Key k);

// The left knob: step sizes in step mode, percentages in continuous mode.
enum class FeedKnob : std::uint8_t {
  Unknown = 0x00,  // not reported yet (the pendant does not say until the knob moves or a key is pressed)
  Step0001 = 0x0D,  // 0.001 mm / 2 %
  Step001 = 0x0E,   // 0.01 mm / 5 %
  Step01 = 0x0F,    // 0.1 mm / 10 %
  Step1 = 0x10,     // 1 mm / 30 %
  Percent60 = 0x1A,
  Percent100 = 0x1B,
  Lead = 0x1C,      // some units send 0x9B: decoded as Lead too
};
const char* to_string(FeedKnob k);
// The step in mm of a knob position (nullopt for 60 %, 100 %, Lead, Unknown).
std::optional<double> knob_step_mm(FeedKnob k);
// The continuous-jog percentage of a knob position (nullopt for Lead, Unknown).
std::optional<int> knob_percent(FeedKnob k);

enum class AxisKnob : std::uint8_t {
  Unknown = 0x00,  // not reported yet
  Off = 0x06,
  X = 0x11,
  Y = 0x12,
  Z = 0x13,
  A = 0x14,  // the -4 stops here
  B = 0x15,
  C = 0x16,
};
const char* to_string(AxisKnob a);
// 0, 1, 2 for X, Y, Z; nullopt for the rest (a 3-axis router has no A, B, C).
std::optional<int> axis_index(AxisKnob a);

enum class ReportKind {
  Input,     // an ordinary report
  Idle,      // keys, knobs and wheel all zero: the pendant is about to sleep
  Sleeping,  // 04 ff ff ff ff ff 81 ff: the pendant sleeps now
};

struct PendantReport {
  ReportKind kind = ReportKind::Input;
  Key key1 = Key::None;
  Key key2 = Key::None;
  bool fn = false;  // Fn is one of the two keys down
  FeedKnob feed_knob = FeedKnob::Unknown;
  AxisKnob axis = AxisKnob::Unknown;
  int wheel = 0;  // signed detents since the previous report
};

// Decodes one report. Returns nullopt and sets `error` (naming the byte, its
// value and what was expected) when the bytes are not a WHB04B report.
std::optional<PendantReport> decode_report(const InputReport& bytes, std::string* error = nullptr);

// "04 00 00 00 0f 11 03 00": the bytes in hex, as in replay files and logs.
std::string hex_bytes(const std::uint8_t* data, std::size_t size);

enum class PendantEventKind {
  KeyPressed,   // key, fn (Fn was held: the macro fn_macro_number(key))
  KeyReleased,  // key
  AxisChanged,  // axis (the new position)
  KnobChanged,  // knob (the new position)
  Wheel,        // detents (signed), with the axis and knob of that report
  Sleep,        // the pendant went to sleep (keys are up, the wheel is still)
  Wake,         // the first report after a sleep (its knob and axis follow as changes)
};
const char* to_string(PendantEventKind k);

struct PendantEvent {
  PendantEventKind kind = PendantEventKind::KeyPressed;
  Key key = Key::None;
  bool fn = false;
  AxisKnob axis = AxisKnob::Unknown;
  FeedKnob knob = FeedKnob::Unknown;
  int detents = 0;
};

// Diffs successive reports. The first ordinary report reports its knob and
// axis positions as changes (from Unknown), so the consumer learns them.
class PendantInputTracker {
 public:
  std::vector<PendantEvent> update(const PendantReport& r);
  // After an unplug: forget everything (the next report starts afresh).
  void reset() { *this = PendantInputTracker{}; }
  bool sleeping() const { return sleeping_; }
  AxisKnob axis() const { return axis_; }
  FeedKnob knob() const { return knob_; }
  bool key_down(Key k) const { return k != Key::None && (held_[0] == k || held_[1] == k); }

 private:
  std::array<Key, 2> held_{Key::None, Key::None};
  AxisKnob axis_ = AxisKnob::Unknown;
  FeedKnob knob_ = FeedKnob::Unknown;
  bool sleeping_ = false;
};

}  // namespace cncstream::pendant
