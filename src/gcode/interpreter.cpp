// Modal G-code interpreter. The order of checks follows GRBL 1.1's parser so
// that a bad block gets the same error code the firmware would send.
#include "cncstream/gcode/interpreter.hpp"

#include <fmt/core.h>

#include <cmath>

#include "cncstream/gcode/grbl_codes.hpp"
#include "cncstream/gcode/line_lexer.hpp"

namespace cncstream::gcode {
namespace {

constexpr double kMaxLineNumber = 10000000;
constexpr double kMaxToolNumber = 255;

// Modal groups (NIST numbering as GRBL uses it).
enum Group : unsigned {
  kGroupNonModal = 0,  // G4 G10 G28 G30 G53 G92
  kGroupMotion,        // G0 G1 G2 G3 G38.x G80
  kGroupPlane,         // G17 G18 G19
  kGroupDistance,      // G90 G91
  kGroupArcDistance,   // G91.1
  kGroupFeedMode,      // G93 G94
  kGroupUnits,         // G20 G21
  kGroupCutterComp,    // G40
  kGroupToolLength,    // G43.1 G49
  kGroupCoordSelect,   // G54..G59
  kGroupPathControl,   // G61
  kGroupProgramFlow,   // M0 M1 M2 M30
  kGroupSpindle,       // M3 M4 M5
  kGroupCoolant,       // M7 M8 M9
};

enum class NonModal { None, Dwell, SetCoordData, GoHome0, SetHome0, GoHome1, SetHome1,
                      AbsoluteOverride, SetOffset, ResetOffset };
enum class AxisCommand { None, NonModal, MotionMode, ToolLength };
enum class Flow { Running, Paused, OptionalStop, End2, End30 };

// Value word bits.
enum ValueWord : unsigned { kF, kI, kJ, kK, kL, kN, kP, kR, kS, kT, kX, kY, kZ };
constexpr unsigned bit(unsigned b) { return 1u << b; }


struct Block {
  ModalState modal;
  NonModal non_modal = NonModal::None;
  Flow flow = Flow::Running;
  double f = 0, l = 0, p = 0, r = 0, s = 0;
  int t = 0;
  double n = 0;
  geometry::Vec3 xyz{}, ijk{};
};

BlockResult fail(const ParserState& state, int status, std::size_t column = 0) {
  BlockResult r;
  r.status = status;
  r.error_column = column;
  r.state = state;
  return r;
}

}  // namespace

void apply_program_end(ParserState& s) {
  s.modal.motion = MotionMode::Linear;
  s.modal.plane = Plane::XY;
  s.modal.incremental = false;
  s.modal.inverse_time = false;
  s.modal.coord_select = 0;
  s.modal.spindle = SpindleState::Off;
  s.modal.flood = false;
  s.modal.mist = false;
  s.coord_system = s.coords.wcs[0];
}

ParserState reset_parser(const ParserState& previous) {
  ParserState s;
  s.coords = previous.coords;
  s.position = previous.position;
  s.coord_system = s.coords.wcs[0];
  return s;
}

BlockResult execute_block(const ParserState& state, std::string_view line,
                          const BlockOptions& options) {
  using namespace grbl;
  Block b;
  b.modal = state.modal;
  const bool jog = options.jog;
  if (jog) {
    b.modal.motion = MotionMode::Linear;
    b.modal.inverse_time = false;
  }

  AxisCommand axis_command = AxisCommand::None;
  unsigned axis_words = 0, ijk_words = 0, command_words = 0, value_words = 0;
  bool set_tool_length = false;

  // ---- step 2: import words, check groups, repeats and negative values ----
  const LexResult lexed = lex_words(line, jog ? 3 : 0);
  // The firmware checks words as it reads them, so a lexing error after a
  // bad word must not hide that word's error: process words first.
  for (const Word& w : lexed.words) {
    const double value = w.value;
    // A value beyond any command or index (1e71, found by tests/fuzz) would
    // overflow int: it becomes one no case matches, so the usual range and
    // unsupported-command errors answer it.
    constexpr double kBeyond = 1e9;
    const bool huge = !(std::fabs(value) < kBeyond);
    const int int_value = huge ? (value < 0 ? -1000000000 : 1000000000) : static_cast<int>(std::trunc(value));
    int mantissa = huge ? 0 : static_cast<int>(std::lround(100 * (value - int_value)));
    unsigned group = 0;
    switch (w.letter) {
      case 'G': {
        switch (int_value) {
          case 10: case 28: case 30: case 92:
            if (mantissa == 0) {
              if (axis_command != AxisCommand::None) return fail(state, kAxisCommandConflict, w.column);
              axis_command = AxisCommand::NonModal;
            }
            [[fallthrough]];
          case 4: case 53:
            group = kGroupNonModal;
            if (int_value == 28 || int_value == 30 || int_value == 92) {
              if (!(mantissa == 0 || mantissa == 10)) return fail(state, kUnsupportedCommand, w.column);
              const bool dot1 = mantissa == 10;
              if (int_value == 28) b.non_modal = dot1 ? NonModal::SetHome0 : NonModal::GoHome0;
              if (int_value == 30) b.non_modal = dot1 ? NonModal::SetHome1 : NonModal::GoHome1;
              if (int_value == 92) b.non_modal = dot1 ? NonModal::ResetOffset : NonModal::SetOffset;
              mantissa = 0;
            } else if (int_value == 4) {
              b.non_modal = NonModal::Dwell;
            } else if (int_value == 10) {
              b.non_modal = NonModal::SetCoordData;
            } else {
              b.non_modal = NonModal::AbsoluteOverride;
            }
            break;
          case 0: case 1: case 2: case 3: case 38:
            if (axis_command != AxisCommand::None) return fail(state, kAxisCommandConflict, w.column);
            axis_command = AxisCommand::MotionMode;
            [[fallthrough]];
          case 80:
            group = kGroupMotion;
            switch (int_value) {
              case 0: b.modal.motion = MotionMode::Rapid; break;
              case 1: b.modal.motion = MotionMode::Linear; break;
              case 2: b.modal.motion = MotionMode::ArcCW; break;
              case 3: b.modal.motion = MotionMode::ArcCCW; break;
              case 80: b.modal.motion = MotionMode::None; break;
              default:  // 38
                if (mantissa == 20) b.modal.motion = MotionMode::ProbeToward;
                else if (mantissa == 30) b.modal.motion = MotionMode::ProbeTowardNoError;
                else if (mantissa == 40) b.modal.motion = MotionMode::ProbeAway;
                else if (mantissa == 50) b.modal.motion = MotionMode::ProbeAwayNoError;
                else return fail(state, kUnsupportedCommand, w.column);
                mantissa = 0;
            }
            break;
          case 17: case 18: case 19:
            group = kGroupPlane;
            b.modal.plane = int_value == 17 ? Plane::XY : (int_value == 18 ? Plane::ZX : Plane::YZ);
            break;
          case 90: case 91:
            if (mantissa == 0) {
              group = kGroupDistance;
              b.modal.incremental = int_value == 91;
            } else {
              group = kGroupArcDistance;
              // Only G91.1 (incremental IJK, GRBL's only arc mode) is accepted.
              if (mantissa != 10 || int_value == 90) return fail(state, kUnsupportedCommand, w.column);
              mantissa = 0;
            }
            break;
          case 93: case 94:
            group = kGroupFeedMode;
            b.modal.inverse_time = int_value == 93;
            break;
          case 20: case 21:
            group = kGroupUnits;
            b.modal.inches = int_value == 20;
            break;
          case 40:
            group = kGroupCutterComp;
            break;
          case 43: case 49:
            group = kGroupToolLength;
            if (axis_command != AxisCommand::None) return fail(state, kAxisCommandConflict, w.column);
            axis_command = AxisCommand::ToolLength;
            if (int_value == 49) {
              b.modal.tool_length_dynamic = false;
            } else if (mantissa == 10) {
              b.modal.tool_length_dynamic = true;
            } else {
              return fail(state, kUnsupportedCommand, w.column);
            }
            mantissa = 0;
            set_tool_length = true;
            break;
          case 54: case 55: case 56: case 57: case 58: case 59:
            group = kGroupCoordSelect;
            b.modal.coord_select = int_value - 54;
            break;
          case 61:
            group = kGroupPathControl;
            if (mantissa != 0) return fail(state, kUnsupportedCommand, w.column);
            break;
          default:
            return fail(state, kUnsupportedCommand, w.column);
        }
        if (mantissa > 0) return fail(state, kCommandValueNotInteger, w.column);
        if (command_words & bit(group)) return fail(state, kModalGroupViolation, w.column);
        command_words |= bit(group);
        break;
      }
      case 'M': {
        if (mantissa > 0) return fail(state, kCommandValueNotInteger, w.column);
        switch (int_value) {
          case 0: case 1: case 2: case 30:
            group = kGroupProgramFlow;
            b.flow = int_value == 0 ? Flow::Paused
                   : int_value == 1 ? Flow::OptionalStop
                   : int_value == 2 ? Flow::End2 : Flow::End30;
            break;
          case 3: case 4: case 5:
            group = kGroupSpindle;
            b.modal.spindle = int_value == 3 ? SpindleState::CW
                            : int_value == 4 ? SpindleState::CCW : SpindleState::Off;
            break;
          case 7: case 8: case 9:
            group = kGroupCoolant;
            if (int_value == 7) b.modal.mist = true;
            if (int_value == 8) b.modal.flood = true;
            if (int_value == 9) b.modal.mist = b.modal.flood = false;
            break;
          default:
            return fail(state, kUnsupportedCommand, w.column);
        }
        if (command_words & bit(group)) return fail(state, kModalGroupViolation, w.column);
        command_words |= bit(group);
        break;
      }
      default: {
        unsigned word = 0;
        switch (w.letter) {
          case 'F': word = kF; b.f = value; break;
          case 'I': word = kI; b.ijk.x = value; ijk_words |= 1; break;
          case 'J': word = kJ; b.ijk.y = value; ijk_words |= 2; break;
          case 'K': word = kK; b.ijk.z = value; ijk_words |= 4; break;
          case 'L': word = kL; b.l = int_value; break;
          case 'N': word = kN; b.n = std::trunc(value); break;
          case 'P': word = kP; b.p = value; break;
          case 'R': word = kR; b.r = value; break;
          case 'S': word = kS; b.s = value; break;
          case 'T':
            word = kT;
            if (value > kMaxToolNumber) return fail(state, kMaxValueExceeded, w.column);
            b.t = int_value;
            break;
          case 'X': word = kX; b.xyz.x = value; axis_words |= 1; break;
          case 'Y': word = kY; b.xyz.y = value; axis_words |= 2; break;
          case 'Z': word = kZ; b.xyz.z = value; axis_words |= 4; break;
          default: return fail(state, kUnsupportedCommand, w.column);
        }
        if (value_words & bit(word)) return fail(state, kWordRepeated, w.column);
        if ((bit(word) & (bit(kF) | bit(kN) | bit(kP) | bit(kT) | bit(kS))) && value < 0)
          return fail(state, kNegativeValue, w.column);
        value_words |= bit(word);
      }
    }
  }
  if (lexed.status != 0) return fail(state, lexed.status, lexed.error_column);
  const bool has_tool_word = (value_words & bit(kT)) != 0;

  // ---- step 3: error-check the block and pre-compute targets -------------
  if (axis_words && axis_command == AxisCommand::None) axis_command = AxisCommand::MotionMode;
  if ((value_words & bit(kN)) && b.n > kMaxLineNumber) return fail(state, kInvalidLineNumber);

  // Feed rate (mm/min after this).
  if (jog) {
    if (!(value_words & bit(kF))) return fail(state, kUndefinedFeedRate);
    if (b.modal.inches) b.f *= kMmPerInch;
  } else if (b.modal.inverse_time) {
    if (axis_command == AxisCommand::MotionMode && b.modal.motion != MotionMode::None &&
        b.modal.motion != MotionMode::Rapid && !(value_words & bit(kF)))
      return fail(state, kUndefinedFeedRate);
  } else if (!state.modal.inverse_time) {
    if (value_words & bit(kF)) {
      if (b.modal.inches) b.f *= kMmPerInch;
    } else {
      b.f = state.feed_rate;
    }
  }  // else: switching G93 -> G94 leaves F undefined unless given.

  if (!(value_words & bit(kS))) b.s = state.spindle_speed;

  if (b.non_modal == NonModal::Dwell) {
    if (!(value_words & bit(kP))) return fail(state, kValueWordMissing);
    value_words &= ~bit(kP);
  }

  int axis0 = 0, axis1 = 1;
  if (b.modal.plane == Plane::ZX) { axis0 = 2; axis1 = 0; }
  if (b.modal.plane == Plane::YZ) { axis0 = 1; axis1 = 2; }

  if (b.modal.inches) {
    for (int i = 0; i < 3; ++i)
      if (axis_words & (1u << i)) component(b.xyz, i) *= kMmPerInch;
  }

  if (axis_command == AxisCommand::ToolLength && b.modal.tool_length_dynamic) {
    if (axis_words != 4u) return fail(state, kG43DynamicAxisError);
  }

  geometry::Vec3 block_coord_system = state.coord_system;
  if (command_words & bit(kGroupCoordSelect)) {
    block_coord_system = state.coords.wcs[static_cast<std::size_t>(b.modal.coord_select)];
  }

  int coord_write_index = -1;  // G10: which stored system changes
  switch (b.non_modal) {
    case NonModal::SetCoordData: {
      if (!axis_words) return fail(state, kNoAxisWords);
      // Like the firmware: only a block with neither P nor L is "missing" a word;
      // a missing L then fails as an unsupported L, a missing P means P0.
      if (!(value_words & (bit(kP) | bit(kL)))) return fail(state, kValueWordMissing);
      // Compared as read: a P beyond int (P888888888880) must not reach the conversion (found by tests/fuzz).
      if (std::trunc(b.p) > 6) return fail(state, kUnsupportedCoordSys);
      const int p = static_cast<int>(std::trunc(b.p));
      const int l = static_cast<int>(b.l);
      if (l != 20) {
        if (l == 2) {
          if (value_words & bit(kR)) return fail(state, kUnsupportedCommand);
        } else {
          return fail(state, kUnsupportedCommand);
        }
      }
      value_words &= ~(bit(kL) | bit(kP));
      coord_write_index = p > 0 ? p - 1 : b.modal.coord_select;
      geometry::Vec3 data = state.coords.wcs[static_cast<std::size_t>(coord_write_index)];
      for (int i = 0; i < 3; ++i) {
        if (!(axis_words & (1u << i))) continue;
        if (l == 20) {
          component(data, i) = component(state.position, i) - component(state.g92, i) - component(b.xyz, i);
          if (i == 2) component(data, i) -= state.tool_length_offset;
        } else {
          component(data, i) = component(b.xyz, i);
        }
      }
      b.ijk = data;
      break;
    }
    case NonModal::SetOffset: {
      if (!axis_words) return fail(state, kNoAxisWords);
      for (int i = 0; i < 3; ++i) {
        if (axis_words & (1u << i)) {
          component(b.xyz, i) = component(state.position, i) - component(block_coord_system, i) - component(b.xyz, i);
          if (i == 2) component(b.xyz, i) -= state.tool_length_offset;
        } else {
          component(b.xyz, i) = component(state.g92, i);
        }
      }
      break;
    }
    default: {
      if (axis_command != AxisCommand::ToolLength && axis_words) {
        for (int i = 0; i < 3; ++i) {
          if (!(axis_words & (1u << i))) {
            component(b.xyz, i) = component(state.position, i);
          } else if (b.non_modal != NonModal::AbsoluteOverride) {
            if (!b.modal.incremental) {
              component(b.xyz, i) += component(block_coord_system, i) + component(state.g92, i);
              if (i == 2) component(b.xyz, i) += state.tool_length_offset;
            } else {
              component(b.xyz, i) += component(state.position, i);
            }
          }
        }
      }
      switch (b.non_modal) {
        case NonModal::GoHome0:
        case NonModal::GoHome1: {
          geometry::Vec3 home = b.non_modal == NonModal::GoHome0 ? state.coords.g28 : state.coords.g30;
          if (axis_words) {
            for (int i = 0; i < 3; ++i)
              if (!(axis_words & (1u << i))) component(home, i) = component(state.position, i);
          } else {
            axis_command = AxisCommand::None;
          }
          b.ijk = home;
          break;
        }
        case NonModal::AbsoluteOverride:
          if (!(b.modal.motion == MotionMode::Rapid || b.modal.motion == MotionMode::Linear))
            return fail(state, kG53InvalidMotionMode);
          break;
        default:
          break;
      }
    }
  }

  // Motion modes.
  double arc_radius = 0;
  bool arc_clockwise = false;
  if (b.modal.motion == MotionMode::None) {
    if (axis_words) return fail(state, kAxisWordsExist);
  } else if (axis_command == AxisCommand::MotionMode) {
    if (b.modal.motion == MotionMode::Rapid) {
      if (!axis_words) axis_command = AxisCommand::None;
    } else {
      if (b.f == 0.0) return fail(state, kUndefinedFeedRate);
      switch (b.modal.motion) {
        case MotionMode::Linear:
          if (!axis_words) axis_command = AxisCommand::None;
          break;
        case MotionMode::ArcCW:
        case MotionMode::ArcCCW: {
          arc_clockwise = b.modal.motion == MotionMode::ArcCW;
          if (!axis_words) return fail(state, kNoAxisWords);
          if (!(axis_words & ((1u << axis0) | (1u << axis1)))) return fail(state, kNoAxisWordsInPlane);
          double x = component(b.xyz, axis0) - component(state.position, axis0);
          double y = component(b.xyz, axis1) - component(state.position, axis1);
          if (value_words & bit(kR)) {
            value_words &= ~bit(kR);
            // GRBL refuses a target equal to the position; one that differs
            // only off the plane (a helix with no turn) would divide by zero
            // below and give the arc a NaN centre (found by tests/fuzz).
            if (x == 0 && y == 0) return fail(state, kInvalidTarget);
            if (b.modal.inches) b.r *= kMmPerInch;
            double h = 4.0 * b.r * b.r - x * x - y * y;
            if (h < 0) return fail(state, kArcRadiusError);
            h = -std::sqrt(h) / std::hypot(x, y);
            if (!arc_clockwise) h = -h;
            if (b.r < 0) {
              h = -h;
              b.r = -b.r;
            }
            b.ijk = geometry::Vec3{};
            component(b.ijk, axis0) = 0.5 * (x - y * h);
            component(b.ijk, axis1) = 0.5 * (y + x * h);
            arc_radius = b.r;
          } else {
            if (!(ijk_words & ((1u << axis0) | (1u << axis1)))) return fail(state, kNoOffsetsInPlane);
            value_words &= ~(bit(kI) | bit(kJ) | bit(kK));
            if (b.modal.inches) {
              for (int i = 0; i < 3; ++i)
                if (ijk_words & (1u << i)) component(b.ijk, i) *= kMmPerInch;
            }
            x -= component(b.ijk, axis0);
            y -= component(b.ijk, axis1);
            const double target_r = std::hypot(x, y);
            arc_radius = std::hypot(component(b.ijk, axis0), component(b.ijk, axis1));
            const double delta_r = std::fabs(target_r - arc_radius);
            if (delta_r > 0.005) {
              if (delta_r > 0.5) return fail(state, kInvalidTarget);
              if (delta_r > 0.001 * arc_radius) return fail(state, kInvalidTarget);
            }
          }
          // Coordinates so large that the arithmetic overflows leave no arc to cut.
          if (!std::isfinite(arc_radius) || !std::isfinite(component(b.ijk, axis0)) || !std::isfinite(component(b.ijk, axis1)))
            return fail(state, kInvalidTarget);
          break;
        }
        default:  // probes
          if (!axis_words) return fail(state, kNoAxisWords);
          if (b.xyz == state.position) return fail(state, kInvalidTarget);
          break;
      }
    }
  }

  // Unused words.
  if (jog) {
    value_words &= ~(bit(kN) | bit(kF));
  } else {
    value_words &= ~(bit(kN) | bit(kF) | bit(kS) | bit(kT));
  }
  if (axis_command != AxisCommand::None) value_words &= ~(bit(kX) | bit(kY) | bit(kZ));
  if (value_words) return fail(state, kUnusedWords);

  // ---- step 4: execute ------------------------------------------------------
  BlockResult out;
  out.state = state;
  ParserState& s = out.state;

  if (jog) {
    const unsigned allowed = bit(kGroupDistance) | bit(kGroupUnits) | bit(kGroupNonModal);
    if (command_words & ~allowed) return fail(state, kInvalidJogCommand);
    if (!(b.non_modal == NonModal::AbsoluteOverride || b.non_modal == NonModal::None))
      return fail(state, kInvalidJogCommand);
    // A jog changes only the parser position; modes stay as they were.
    out.actions.push_back(JogMove{state.position, b.xyz, b.f});
    s.position = b.xyz;
    return out;
  }

  s.line_number = static_cast<std::int32_t>(b.n);
  s.modal.inverse_time = b.modal.inverse_time;
  s.feed_rate = b.f;
  const bool spindle_mode_changes = s.modal.spindle != b.modal.spindle;
  if (s.spindle_speed != b.s) {
    s.spindle_speed = b.s;
    if (s.modal.spindle != SpindleState::Off && !spindle_mode_changes)
      out.actions.push_back(SpindleChange{s.modal.spindle, s.spindle_speed});
  }
  if (has_tool_word) s.tool = b.t;
  if (spindle_mode_changes) {
    s.modal.spindle = b.modal.spindle;
    out.actions.push_back(SpindleChange{s.modal.spindle, s.spindle_speed});
  }
  if (s.modal.flood != b.modal.flood || s.modal.mist != b.modal.mist) {
    s.modal.flood = b.modal.flood;
    s.modal.mist = b.modal.mist;
    out.actions.push_back(CoolantChange{s.modal.flood, s.modal.mist});
  }
  if (b.non_modal == NonModal::Dwell) out.actions.push_back(Dwell{b.p});
  s.modal.plane = b.modal.plane;
  s.modal.inches = b.modal.inches;
  if (set_tool_length) {
    s.modal.tool_length_dynamic = b.modal.tool_length_dynamic;
    const double tlo = b.modal.tool_length_dynamic ? b.xyz.z : 0.0;
    if (s.tool_length_offset != tlo) {
      s.tool_length_offset = tlo;
      out.actions.push_back(WorkOffsetChange{});
    }
  }
  if (s.modal.coord_select != b.modal.coord_select) {
    s.modal.coord_select = b.modal.coord_select;
    s.coord_system = block_coord_system;
    out.actions.push_back(WorkOffsetChange{});
  }
  s.modal.incremental = b.modal.incremental;

  switch (b.non_modal) {
    case NonModal::SetCoordData:
      s.coords.wcs[static_cast<std::size_t>(coord_write_index)] = b.ijk;
      out.actions.push_back(CoordinateWrite{coord_write_index, b.ijk});
      if (s.modal.coord_select == coord_write_index) {
        s.coord_system = b.ijk;
        out.actions.push_back(WorkOffsetChange{});
      }
      break;
    case NonModal::GoHome0:
    case NonModal::GoHome1:
      if (axis_command != AxisCommand::None) {
        out.actions.push_back(LinearMove{s.position, b.xyz, true, 0, s.line_number});
        s.position = b.xyz;
      }
      out.actions.push_back(LinearMove{s.position, b.ijk, true, 0, s.line_number});
      s.position = b.ijk;
      break;
    case NonModal::SetHome0:
      s.coords.g28 = s.position;
      out.actions.push_back(CoordinateWrite{6, s.position});
      break;
    case NonModal::SetHome1:
      s.coords.g30 = s.position;
      out.actions.push_back(CoordinateWrite{7, s.position});
      break;
    case NonModal::SetOffset:
      s.g92 = b.xyz;
      out.actions.push_back(WorkOffsetChange{});
      break;
    case NonModal::ResetOffset:
      s.g92 = geometry::Vec3{};
      out.actions.push_back(WorkOffsetChange{});
      break;
    default:
      break;
  }

  s.modal.motion = b.modal.motion;
  if (s.modal.motion != MotionMode::None && axis_command == AxisCommand::MotionMode) {
    switch (s.modal.motion) {
      case MotionMode::Rapid:
        out.actions.push_back(LinearMove{s.position, b.xyz, true, 0, s.line_number});
        break;
      case MotionMode::Linear: {
        double feed = s.feed_rate;
        if (s.modal.inverse_time) feed = s.feed_rate * norm(b.xyz - s.position);
        out.actions.push_back(LinearMove{s.position, b.xyz, false, feed, s.line_number});
        break;
      }
      case MotionMode::ArcCW:
      case MotionMode::ArcCCW: {
        ArcMove arc;
        arc.from = s.position;
        arc.to = b.xyz;
        arc.center = s.position;
        component(arc.center, axis0) += component(b.ijk, axis0);
        component(arc.center, axis1) += component(b.ijk, axis1);
        arc.radius = arc_radius;
        arc.plane = s.modal.plane;
        arc.clockwise = arc_clockwise;
        arc.feed = s.feed_rate;
        arc.inverse_time = s.modal.inverse_time;
        arc.line_number = s.line_number;
        out.actions.push_back(arc);
        break;
      }
      default: {
        ProbeMove p;
        p.from = s.position;
        p.to = b.xyz;
        p.feed = s.modal.inverse_time ? s.feed_rate * norm(b.xyz - s.position) : s.feed_rate;
        p.toward = s.modal.motion == MotionMode::ProbeToward ||
                   s.modal.motion == MotionMode::ProbeTowardNoError;
        p.error_on_fail = s.modal.motion == MotionMode::ProbeToward ||
                          s.modal.motion == MotionMode::ProbeAway;
        p.line_number = s.line_number;
        out.actions.push_back(p);
      }
    }
    // The parser assumes the target is reached; a probe's machine re-syncs it.
    s.position = b.xyz;
  }
  switch (b.flow) {
    case Flow::Paused:
      out.actions.push_back(ProgramPause{false});
      break;
    case Flow::End2:
    case Flow::End30: {
      apply_program_end(s);
      out.actions.push_back(ProgramEnd{b.flow == Flow::End2 ? 2 : 30});
      break;
    }
    default:
      break;
  }
  return out;
}

std::string format_modes(const ParserState& s) {
  std::string out = "[GC:";
  switch (s.modal.motion) {
    case MotionMode::Rapid: out += "G0"; break;
    case MotionMode::Linear: out += "G1"; break;
    case MotionMode::ArcCW: out += "G2"; break;
    case MotionMode::ArcCCW: out += "G3"; break;
    case MotionMode::ProbeToward: out += "G38.2"; break;
    case MotionMode::ProbeTowardNoError: out += "G38.3"; break;
    case MotionMode::ProbeAway: out += "G38.4"; break;
    case MotionMode::ProbeAwayNoError: out += "G38.5"; break;
    case MotionMode::None: out += "G80"; break;
  }
  out += " G" + std::to_string(54 + s.modal.coord_select);
  out += s.modal.plane == Plane::XY ? " G17" : (s.modal.plane == Plane::ZX ? " G18" : " G19");
  out += s.modal.inches ? " G20" : " G21";
  out += s.modal.incremental ? " G91" : " G90";
  out += s.modal.inverse_time ? " G93" : " G94";
  out += s.modal.spindle == SpindleState::CW ? " M3" : (s.modal.spindle == SpindleState::CCW ? " M4" : " M5");
  if (!s.modal.flood && !s.modal.mist) out += " M9";
  if (s.modal.mist) out += " M7";
  if (s.modal.flood) out += " M8";
  out += " T" + std::to_string(s.tool);
  const double feed = s.modal.inches ? s.feed_rate / kMmPerInch : s.feed_rate;
  out += fmt::format(" F{:.0f} S{:.0f}]", feed, s.spindle_speed);
  return out;
}

}  // namespace cncstream::gcode
