#pragma once
// The WHB04B's LCD: what it shows, encoded without any I/O. The pendant takes
// a 21-byte payload (little-endian, packed) in three 8-byte HID feature
// reports (report id 0x06 and 7 payload bytes each, SET_REPORT wValue
// 0x0306), and shows it until the next one; it renders the step size or the
// percentage itself from its knob, we only say which of the two to show.
//
//   [0-1] 0xfdfe  [2] seed 0xfe  [3] flags
//   [4-7] [8-11] [12-15] three coordinates: u16 integer part, then u16 with
//         the fraction x 10000 in bits 0-14 and the sign in bit 15
//   [16-17] feed (u16)  [18-19] spindle (u16)  [20] 0
// Flags: bits 0-1 the mode line (0 "CON: x%", 1 "STP: x", 2 "MPG: x%",
// 3 "x%"), bit 6 "RESET" instead of the mode line, bit 7 work-coordinate
// labels (X1 Y1 Z1; machine coordinates: X Y Z). Bits 2-5: unknown, 0.
#include <array>
#include <cstdint>

namespace cncstream::pendant {

enum class DisplayMode : std::uint8_t { Continuous = 0, Step = 1, Mpg = 2, Percent = 3 };

struct DisplayState {
  std::array<double, 3> coordinates{};  // mm, the three rows (X Y Z; A B C when the knob is on A-C)
  bool work_coordinates = true;
  DisplayMode mode = DisplayMode::Step;
  bool reset = false;       // "RESET" instead of the mode line (alarm, disconnected)
  unsigned feed = 100;      // shown as F: the feed override, %
  unsigned spindle = 100;   // shown as S: the spindle override, %
};

using DisplayPayload = std::array<std::uint8_t, 21>;
using FeatureReport = std::array<std::uint8_t, 8>;
using DisplayReports = std::array<FeatureReport, 3>;

// One coordinate's four bytes: rounded to 0.0001 mm; magnitudes beyond
// 65535.9999 are shown as that; a value that rounds to zero has no sign.
std::array<std::uint8_t, 4> encode_coordinate(double mm);
DisplayPayload encode_display(const DisplayState& s);
DisplayReports split_into_reports(const DisplayPayload& p);
inline DisplayReports encode_display_reports(const DisplayState& s) { return split_into_reports(encode_display(s)); }

}  // namespace cncstream::pendant
