#pragma once
// The modal state a restart needs, tracked line by line as lines are answered
// (units, distance mode, plane, WCS, feed, spindle, coolant, tool). This is a
// small tracker for the journal, not a G-code interpreter: it only follows the
// words that change modal state.
#include <optional>
#include <string>
#include <string_view>

#include "cncstream/protocol/status_report.hpp"

namespace cncstream::protocol {

struct ModalState {
  std::string units = "G21";
  std::string distance = "G90";
  std::string plane = "G17";
  std::string wcs = "G54";
  std::string motion = "G0";
  double feed = 0;
  double spindle_speed = 0;
  std::string spindle = "M5";
  bool flood = false, mist = false;
  int tool = 0;
  std::optional<Axes> wco;  // work offset reported by the controller (MPos - WPos)

  // Applies a cleaned line's modal words.
  void apply(std::string_view cleaned_line);
  std::string coolant() const;  // "M9", "M7", "M8" or "M7M8"
  // A G-code preamble that restores this state (for a restart from a line).
  std::string preamble() const;
  std::string to_json() const;
};

}  // namespace cncstream::protocol
