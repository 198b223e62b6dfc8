#pragma once
// Generalized APT cutter for 3-axis work, tool axis +Z.
// Thesis notation: r1 = corner radius (rk), r2 = core radius (rc), R = rc + rk.
//   flat: rk = 0, rc = R     ball: rk = R, rc = 0     bull: 0 < rk < R.
#include <stdexcept>
#include <string>
#include <string_view>

namespace cncstream {

enum class CutterType { Flat, Ball, Bull };

struct Cutter {
  CutterType type = CutterType::Ball;
  double radius = 0;         // R, mm
  double corner_radius = 0;  // rk, mm

  double diameter() const { return 2 * radius; }
  double core_radius() const { return radius - corner_radius; }  // rc

  // Height of the cutter surface above its tip at horizontal distance rho
  // from the axis (0 <= rho <= R). The tip is the lowest point.
  double profile_height(double rho) const;
  // Height of the profile at rho = R: where the side wall begins.
  double profile_top() const { return corner_radius; }

  static Cutter flat(double diameter);
  static Cutter ball(double diameter);
  static Cutter bull(double diameter, double corner_radius);

  std::string spec() const;         // canonical spec string, e.g. "bull:6:1"
  std::string description() const;  // "6 mm bull-nose, 1 mm corner radius"
};

// The cutter grown by `leave` all round (its Minkowski sum with a ball of
// radius leave, the tip moved down by leave): ball R -> ball R + leave, flat
// R -> bull (R + leave, corner leave), bull (R, r) -> bull (R + leave, r +
// leave). Where the grown cutter touches a part with its tip at z, the
// cutter itself, tip at z + leave, keeps at least `leave` from the part in
// every direction. leave = 0 gives the cutter itself. Throws
// std::invalid_argument for a negative or non-finite leave.
Cutter grown_cutter(const Cutter& cutter, double leave);

class CutterSpecError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// "flat:6", "ball:3.175", "bull:6:1", "ball:1/8in", "bull:0.25in:0.03in",
// "flat:6mm". Numbers may be decimals or fractions; a unit suffix (mm, in)
// applies to that number. A bull with corner radius 0 is a flat, with corner
// radius = R a ball.
Cutter parse_cutter_spec(std::string_view spec);

}  // namespace cncstream
