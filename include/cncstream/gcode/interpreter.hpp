#pragma once
// A modal G-code interpreter with GRBL 1.1's semantics and error codes.
//
// execute_block() is pure: it takes the parser state and one cleaned line
// (see line_lexer.hpp) and returns either an error code with the state left
// untouched, or the new state plus the actions the block asks for, in the
// firmware's order of execution. Positions are machine coordinates in mm;
// feed rates are mm/min (inverse-time feeds are converted per move).
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "cncstream/geometry/vec3.hpp"

namespace cncstream::gcode {

enum class MotionMode { Rapid, Linear, ArcCW, ArcCCW, ProbeToward, ProbeTowardNoError, ProbeAway,
                        ProbeAwayNoError, None };
enum class Plane { XY, ZX, YZ };
enum class SpindleState { Off, CW, CCW };

// G20's unit: program lengths and feeds in inches are this many mm.
inline constexpr double kMmPerInch = 25.4;

struct ModalState {
  MotionMode motion = MotionMode::Rapid;
  Plane plane = Plane::XY;
  bool incremental = false;     // G91
  bool inverse_time = false;    // G93
  bool inches = false;          // G20
  int coord_select = 0;         // 0..5 = G54..G59
  SpindleState spindle = SpindleState::Off;
  bool flood = false;           // M8
  bool mist = false;            // M7
  bool tool_length_dynamic = false;  // G43.1 active (else G49)
};

// Stored coordinate data (EEPROM on the firmware): G54..G59, G28, G30.
struct CoordinateTable {
  std::array<geometry::Vec3, 6> wcs{};
  geometry::Vec3 g28{};
  geometry::Vec3 g30{};
};

struct ParserState {
  ModalState modal;
  geometry::Vec3 position{};          // where the parser thinks the tool is (machine mm)
  double feed_rate = 0;     // mm/min (G94) or inverse-time value (G93)
  double spindle_speed = 0; // rpm
  int tool = 0;
  std::int32_t line_number = 0;
  geometry::Vec3 coord_system{};      // active WCS offset
  geometry::Vec3 g92{};               // G92 offset
  double tool_length_offset = 0;  // G43.1 Z
  CoordinateTable coords;

  // Work coordinate offset: WPos = MPos - wco().
  geometry::Vec3 wco() const { return coord_system + g92 + geometry::Vec3{0, 0, tool_length_offset}; }
  geometry::Vec3 work_position() const { return position - wco(); }
};

// ---- actions -------------------------------------------------------------
struct LinearMove {
  geometry::Vec3 from, to;
  bool rapid = false;
  double feed = 0;  // mm/min; for rapids 0 (the machine uses its max rates)
  std::int32_t line_number = 0;
};
struct ArcMove {
  geometry::Vec3 from, to;
  geometry::Vec3 center;  // in the plane; the linear axis of center is unused
  double radius = 0;
  Plane plane = Plane::XY;
  bool clockwise = true;
  double feed = 0;            // mm/min, or the inverse-time value if inverse_time
  bool inverse_time = false;  // then the whole arc takes 1/feed minutes
  std::int32_t line_number = 0;
};
struct ProbeMove {
  geometry::Vec3 from, to;
  double feed = 0;
  bool toward = true;        // G38.2/3 (else away: G38.4/5)
  bool error_on_fail = true; // G38.2/4 (else G38.3/5)
  std::int32_t line_number = 0;
};
struct Dwell { double seconds = 0; };
struct SpindleChange { SpindleState state = SpindleState::Off; double rpm = 0; };
struct CoolantChange { bool flood = false; bool mist = false; };
struct ProgramPause { bool optional = false; };  // M0 (M1 is ignored by GRBL, never emitted)
struct ProgramEnd { int code = 2; };             // M2 / M30
// Persistent coordinate data was written (G10, G28.1, G30.1): index 0..5 =
// G54..G59, 6 = G28, 7 = G30. The machine stores it (EEPROM).
struct CoordinateWrite { int index = 0; geometry::Vec3 value; };
struct WorkOffsetChange {};  // WCO changed (status reports refresh WCO)
struct JogMove { geometry::Vec3 from, to; double feed = 0; };

using Action = std::variant<LinearMove, ArcMove, ProbeMove, Dwell, SpindleChange, CoolantChange,
                            ProgramPause, ProgramEnd, CoordinateWrite, WorkOffsetChange, JogMove>;

struct BlockOptions {
  bool jog = false;  // the line starts with "$J=" (words begin after it)
};

struct BlockResult {
  int status = 0;  // 0 = ok, else GRBL error code
  std::size_t error_column = 0;  // column of a lexing error, when known
  ParserState state;
  std::vector<Action> actions;
  bool ok() const { return status == 0; }
};

// Interprets one cleaned line (upper case, no spaces or comments).
BlockResult execute_block(const ParserState& state, std::string_view cleaned,
                          const BlockOptions& options = {});

// Parser state after a program end (M2/M30): GRBL resets only some groups.
void apply_program_end(ParserState& state);

// A fresh parser (power-up / soft reset) keeping the stored coordinate data
// and the position: modal defaults, G92 cleared, G54 loaded.
ParserState reset_parser(const ParserState& previous);

// "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]" without the brackets' prefix,
// i.e. the text the firmware prints for $G.
std::string format_modes(const ParserState& state);

}  // namespace cncstream::gcode
