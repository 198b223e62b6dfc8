#include "cncstream/gcode/modal_words.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace cncstream::gcode {

namespace {

const char* motion_word(MotionMode m) {
  switch (m) {
    case MotionMode::Rapid: return "G0";
    case MotionMode::Linear: return "G1";
    case MotionMode::ArcCW: return "G2";
    case MotionMode::ArcCCW: return "G3";
    case MotionMode::ProbeToward: return "G38.2";
    case MotionMode::ProbeTowardNoError: return "G38.3";
    case MotionMode::ProbeAway: return "G38.4";
    case MotionMode::ProbeAwayNoError: return "G38.5";
    case MotionMode::None: return "G80";
  }
  return "G0";
}

}  // namespace

ModalWords modal_words(const ParserState& s) {
  ModalWords w;
  w.units = s.modal.inches ? "G20" : "G21";
  w.distance = s.modal.incremental ? "G91" : "G90";
  w.plane = s.modal.plane == Plane::XY ? "G17" : s.modal.plane == Plane::ZX ? "G18" : "G19";
  static const char* const kWcs[] = {"G54", "G55", "G56", "G57", "G58", "G59"};
  w.wcs = kWcs[std::clamp(s.modal.coord_select, 0, 5)];
  w.motion = motion_word(s.modal.motion);
  w.feed_mode = s.modal.inverse_time ? "G93" : "G94";
  w.spindle = s.modal.spindle == SpindleState::CW ? "M3" : s.modal.spindle == SpindleState::CCW ? "M4" : "M5";
  w.coolant = s.modal.mist && s.modal.flood ? "M7M8" : s.modal.mist ? "M7" : s.modal.flood ? "M8" : "M9";
  w.feed = s.modal.inches && !s.modal.inverse_time ? s.feed_rate / kMmPerInch : s.feed_rate;
  w.spindle_speed = s.spindle_speed;
  w.tool = s.tool;
  return w;
}

ParserState modal_from_words(const ModalWords& w) {
  // Each group on its own block, through the interpreter itself: the same
  // rules as the program's own lines (a motion word needs no axis words).
  ParserState s;
  // The motion mode is set directly: a G1 block without axis words and
  // without a feed is refused by the interpreter, yet the mode is valid.
  std::vector<std::string> blocks{w.units, w.distance, w.plane, w.wcs, w.feed_mode, w.spindle};
  if (w.coolant == "M7M8") {
    blocks.emplace_back("M7");
    blocks.emplace_back("M8");
  } else {
    blocks.push_back(w.coolant);
  }
  blocks.push_back(fmt::format("F{:.6g}S{:.6g}T{}", w.feed, w.spindle_speed, w.tool));
  for (const auto& b : blocks) {
    if (b.empty()) continue;  // an older record without this group: the default holds
    auto r = execute_block(s, b);
    if (!r.ok()) throw std::invalid_argument("modal state word '" + b + "' is not valid G-code (error " +
                                             std::to_string(r.status) + ")");
    s = r.state;
  }
  if (w.motion.empty()) return s;
  for (const MotionMode m : {MotionMode::Rapid, MotionMode::Linear, MotionMode::ArcCW, MotionMode::ArcCCW,
                             MotionMode::ProbeToward, MotionMode::ProbeTowardNoError, MotionMode::ProbeAway,
                             MotionMode::ProbeAwayNoError, MotionMode::None})
    if (w.motion == motion_word(m)) {
      s.modal.motion = m;
      return s;
    }
  throw std::invalid_argument("modal state word '" + w.motion + "' is not a motion mode");
}

std::string modal_json(const ParserState& s) {
  const ModalWords w = modal_words(s);
  return fmt::format(
      "{{\"units\":\"{}\",\"distance\":\"{}\",\"plane\":\"{}\",\"wcs\":\"{}\",\"motion\":\"{}\","
      "\"feed_mode\":\"{}\",\"feed\":{:.6g},\"spindle_speed\":{:.6g},\"spindle\":\"{}\",\"coolant\":\"{}\","
      "\"tool\":{}}}",
      w.units, w.distance, w.plane, w.wcs, w.motion, w.feed_mode, w.feed, w.spindle_speed, w.spindle, w.coolant,
      w.tool);
}

}  // namespace cncstream::gcode
