#pragma once
// Setting work zero with a corner touch plate (GRBL family): a pure routine
// (protocol/machine_routine.hpp) the machine session runs outside a job.
//
// The plate lies on the stock's top at its X-min/Y-min corner, its lips down
// the stock's left and front sides, so its outer walls stand `lip` outside the
// stock's edges. The operator puts the bit over the plate's top, within the
// Z travel above it. Z first (the plate's top: stock top = trigger −
// thickness), then X (the bit lowered beside the left wall, probing +X: edge =
// trigger + cutter radius + lip), then Y (beside the front wall, probing +Y).
// Each probe: the input checked clear first, a bounded fast G38.2, back off,
// the input clear again, a slow G38.2; the trigger read from [PRB:...], never
// from the status (which is past it by the deceleration). Every travel runs
// at a G53 height `clearance` above the plate's top; each lowering beside the
// plate is a G38.3, so something under the bit stops it. The result (machine
// coordinates of the corner and the offset it gives) is shown to the operator
// before it is written to the active work offset (G10 L2, accounting for G92
// and the tool-length offset from $#), then read back with $#.
//
// XY: the plate's top is touched only to know how low to go beside it; Z and
// the offset's Z are left alone. Z: the top only.
#include <optional>
#include <string>

#include "cncstream/geometry/vec3.hpp"
#include "cncstream/protocol/machine_routine.hpp"

namespace cncstream::protocol {

enum class CornerAxes { XYZ, XY, Z };
const char* to_string(CornerAxes a);
// "xyz" (or "corner"), "xy", "z"; throws std::invalid_argument naming the text.
CornerAxes parse_corner_axes(const std::string& text);

struct CornerPlate {
  double thickness = 5;  // its top above the stock's top, mm
  double lip = 3;        // its outer walls stand this far outside the stock's edges, mm
  double size = 50;      // its top's extent from the outer walls, mm
};

struct CornerProbeConfig {
  CornerAxes axes = CornerAxes::XYZ;
  CornerPlate plate;
  double tool_radius = 3;   // the cutter in the spindle, mm
  double z_travel = 25;     // the longest search down to the plate's top from the start
  double fast_feed = 150, slow_feed = 20;  // mm/min
  double retract = 2;       // back off between the fast and the slow probe
  double clearance = 5;     // travel height above the plate's top, and the distance kept beside it
  double side_depth = 4;    // the tip below the plate's top when probing a wall (< thickness + lip depth)
};
// Refuses what cannot work (names the field): non-positive sizes, feeds,
// travels; a side depth not below the plate's top.
void validate(const CornerProbeConfig& c);

struct CornerProbeResult {
  // Machine coordinates of what was found (for the tool in the spindle: the
  // spindle's Z with its tip on the stock's top).
  std::optional<double> edge_x, edge_y, top_z;
  int wcs = 0;            // the active work offset, 0..5 for G54..G59
  geometry::Vec3 offset_before{};   // its value read before
  geometry::Vec3 offset_written{};  // the value written (the axes not probed: unchanged)
  bool applied = false;   // written and read back
};

class CornerProbeRoutine final : public MachineRoutine {
 public:
  explicit CornerProbeRoutine(CornerProbeConfig config);
  const char* name() const override { return "corner probe"; }
  const CornerProbeResult& result() const { return result_; }

 private:
  void build() override;
  // A fast then a slow probe along `axis` (0 X, 1 Y, 2 Z) by `dir`·travel;
  // the slow trigger's coordinate goes to *out.
  void add_probe(int axis, double dir, double travel, double* out);
  void add_input_clear(const char* when);
  void add_lower_beside();

  CornerProbeConfig cfg_;
  CornerProbeResult result_;
  geometry::Vec3 start_{};
  double top_trigger_ = 0, x_trigger_ = 0, y_trigger_ = 0;
};

}  // namespace cncstream::protocol
