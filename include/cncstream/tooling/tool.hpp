#pragma once
// A tool the shop owns: its shape (as a cutter spec string plus typed
// dimensions), flutes, stick-out and cutting data per material. The shape's
// spec is what the CAM engines take (cam/cutter.hpp parses flat, ball and
// bull; V-bits and tapered balls come with the exact engine's composite
// cutters), so the library never needs its own copy of a cutter.
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace cncstream::tooling {

enum class ToolShape { Flat, Ball, Bull, VBit, TaperedBall };

// Dimensions in mm, angles in degrees.
//   flat, ball:  diameter
//   bull:        diameter, corner_radius
//   vbit:        angle (included), diameter (top of the cone), tip_diameter (flat tip width, 0: pointed)
//   taper:       tip_diameter (the ball's), angle (per side), diameter (top of the flutes; 0: not given)
struct ToolGeometry {
  ToolShape shape = ToolShape::Flat;
  double diameter = 0;
  double corner_radius = 0;
  double angle = 0;
  double tip_diameter = 0;

  // "flat:6", "ball:3.175", "bull:6:1", "vbit:60:12.7", "vbit:90:12:0.2", "taper:1:5:3.175", "taper:1:5".
  std::string spec() const;
  // "1 mm tapered ball-nose, 5° per side, 3.175 mm at the top".
  std::string description() const;
  // The diameter the tool cuts with at most (its top diameter; a taper
  // without one: its tip).
  double cutting_diameter() const;
  // Flat, ball or bull-nose: the shapes every CL engine already knows.
  bool is_apt() const { return shape == ToolShape::Flat || shape == ToolShape::Ball || shape == ToolShape::Bull; }
};

const char* shape_name(ToolShape s);  // "flat", "ball", "bull", "vbit", "taper"
std::optional<ToolShape> shape_from_name(std::string_view name);

// Every shape's spec: flat:D, ball:D, bull:D:r (cam's syntax: 1/8in, 6mm,
// fractions), vbit:ANGLE:D[:TIP_W] (included angle), taper:TIP_D:ANGLE[:TOP_D]
// (angle per side, as OCL and the exact engine take it; the library formats
// that give the included angle are halved on import).
// Throws std::invalid_argument naming the spec and the part that is wrong.
ToolGeometry parse_tool_spec(std::string_view spec);

// Cutting data of a tool in one material (from the library or an import).
// Unset fields come from the material table (tooling/feeds_speeds.hpp).
struct CuttingData {
  std::string material;             // as in the material table: "walnut", "mdf", "hardwood" ...
  std::optional<double> rpm;        // rev/min
  std::optional<double> feed;       // mm/min
  std::optional<double> plunge_feed;
  std::optional<double> chip_load;  // mm per tooth
  std::optional<double> surface_speed;  // m/min
  std::optional<double> stepdown;   // mm
  std::optional<double> stepover;   // mm
};

// Each optional value of the cutting data with its key (the library file's
// and the API's): f(key, value).
template <class Data, class F>
  requires std::is_same_v<std::remove_const_t<Data>, CuttingData>
void for_each_value(Data& c, F&& f) {
  f("rpm", c.rpm);
  f("feed", c.feed);
  f("plunge_feed", c.plunge_feed);
  f("chip_load", c.chip_load);
  f("surface_speed", c.surface_speed);
  f("stepdown", c.stepdown);
  f("stepover", c.stepover);
}

struct Tool {
  int number = 0;  // the T number; 1..9999, unique in a library
  std::string name;
  ToolGeometry geometry;
  int flutes = 2;
  double flute_length = 0;     // mm; 0: not known
  double overall_length = 0;   // mm; 0: not known
  double stick_out = 0;        // from the collet, mm; 0: not known
  double shank_diameter = 0;   // mm; 0: not known
  double length_offset = 0;    // the controller's tool length offset (LinuxCNC Z), mm; 0: not known
  std::string notes;
  std::vector<CuttingData> cutting;

  // The data for `material` (exact, case-insensitive), or null.
  const CuttingData* cutting_for(std::string_view material) const;
};

// Throws std::invalid_argument "<what>: ..." for a tool that cannot be
// used: a number out of range, no name, a shape's dimension that does not
// make sense, flutes out of 1..12, a negative length.
void check_tool(const Tool& t);

}  // namespace cncstream::tooling
