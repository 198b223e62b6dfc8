#pragma once
// Axisymmetric cutters for 3-axis work, tool axis +Z, tip = lowest point.
// Generalized APT (thesis notation: r1 = corner radius (rk), r2 = core radius
// (rc), R = rc + rk):
//   flat: rk = 0, rc = R     ball: rk = R, rc = 0     bull: 0 < rk < R.
// And the tools a sign maker owns:
//   V-bit: a cone of half-angle a (per side) with an optional flat tip of
//     radius rt, up to the top radius R; h = (rho - rt) / tan(a).
//   tapered ball-nose: a ball of radius r (= corner_radius) on a cone of
//     half-angle a tangent to it (at rho = r cos a, height r (1 - sin a)), up
//     to the top radius R.
// Above the top of the flutes (profile_top()) every cutter is a cylinder of
// radius R: the shank is taken as no wider than the flutes (a shank wider
// than R has no spec and is refused where a Cutter is built from a library).
// Every profile is a list of bands (profile()): each a cone piece (slope 0:
// a flat disc or annulus) or a circle arc (sphere or torus), convex and
// non-decreasing in rho, which is what the exact CL engine relies on.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>

namespace cncstream::cam {

enum class CutterType { Flat, Ball, Bull, VBit, TaperedBall };

// One band of a profile over rho in [rho0, rho1]:
//   Cone: h = h0 + slope * (rho - rho0)
//   Arc:  h = zc - sqrt(r^2 - (rho - a)^2), the lower outer quarter of the
//         circle of radius r centred at (a, zc) (a = 0: a sphere, else a torus)
// h0 is the height at rho0 for both kinds. sin0, sin1: the sine of the
// surface's tilt from horizontal at rho0 and rho1 (its normal's |n_xy|).
struct ProfileBand {
  enum class Kind { Cone, Arc };
  Kind kind = Kind::Cone;
  double rho0 = 0, rho1 = 0, h0 = 0;
  double slope = 0;           // Cone
  double a = 0, zc = 0, r = 0;  // Arc
  double sin0 = 0, sin1 = 0;

  // Inline: the CL engine's point queries call it for every primitive.
  double h(double rho) const {
    if (kind == Kind::Cone) return h0 + slope * (rho - rho0);
    const double u = std::clamp(rho - a, 0.0, r);
    return zc - std::sqrt(std::max(0.0, (r - u) * (r + u)));
  }
};

struct CutterProfile {
  static constexpr std::size_t kMaxBands = 6;
  std::array<ProfileBand, kMaxBands> band{};
  std::size_t count = 0;
  double R = 0;    // radius of the last band's end (the reach)
  double top = 0;  // h(R)

  // h(rho) for 0 <= rho <= R (clamped at both ends).
  double h(double rho) const {
    if (!(rho > 0)) rho = 0;
    if (rho >= R) return top;
    for (std::size_t k = 0; k < count; ++k)
      if (rho <= band[k].rho1) return band[k].h(std::max(rho, band[k].rho0));
    return top;
  }
};

struct Cutter {
  CutterType type = CutterType::Ball;
  double radius = 0;         // R, mm (V-bit, tapered ball: the top of the flutes)
  double corner_radius = 0;  // rk, mm (tapered ball: the ball tip's radius)
  double half_angle_deg = 0; // V-bit, tapered ball: the cone's angle from the axis, per side
  double tip_radius = 0;     // V-bit: radius of the flat tip (0: pointed)
  double grown = 0;          // V-bit, tapered ball: grown by this all round (grown_cutter)

  double diameter() const { return 2 * radius; }
  // Radius of the flat bottom (V-bit: the flat tip; tapered ball: none).
  double core_radius() const {
    return type == CutterType::VBit ? tip_radius : type == CutterType::TaperedBall ? 0.0 : radius - corner_radius;
  }
  // Whether the profile is a generalized APT one (flat, ball, bull-nose).
  bool is_apt() const { return type == CutterType::Flat || type == CutterType::Ball || type == CutterType::Bull; }
  // The radius of the tip's rounding, from which scallops between adjacent
  // passes grow (ball, bull: rk; tapered ball: the ball; V-bit: 0, or the
  // grown radius).
  double tip_round_radius() const { return is_apt() ? corner_radius : type == CutterType::TaperedBall ? corner_radius + grown : grown; }

  // Height of the cutter surface above its tip at horizontal distance rho
  // from the axis (0 <= rho <= R). The tip is the lowest point.
  double profile_height(double rho) const;
  // Height of the profile at rho = R: where the side wall begins (the top of
  // the flutes for a V-bit or tapered ball).
  double profile_top() const;
  // The profile as bands (see ProfileBand); throws std::invalid_argument for
  // dimensions no cutter has.
  CutterProfile profile() const;

  static Cutter flat(double diameter);
  static Cutter ball(double diameter);
  static Cutter bull(double diameter, double corner_radius);
  // included_angle_deg in (0, 180); tip_width the flat tip's diameter.
  static Cutter vbit(double included_angle_deg, double diameter, double tip_width = 0);
  // Ball tip diameter, cone angle per side in (0, 90), diameter at the top of
  // the flutes (> tip diameter).
  static Cutter tapered_ball(double tip_diameter, double half_angle_deg, double top_diameter);

  std::string spec() const;         // canonical spec string, e.g. "bull:6:1"
  std::string description() const;  // "6 mm bull-nose, 1 mm corner radius"
};

// The cutter grown by `leave` all round (its Minkowski sum with a ball of
// radius leave, the tip moved down by leave): ball R -> ball R + leave, flat
// R -> bull (R + leave, corner leave), bull (R, r) -> bull (R + leave, r +
// leave); a V-bit or tapered ball keeps its type with `grown` raised (its
// profile offset by leave: corners become arcs of radius leave). Where the
// grown cutter touches a part with its tip at z, the cutter itself, tip at
// z + leave, keeps at least `leave` from the part in every direction.
// leave = 0 gives the cutter itself. Throws std::invalid_argument for a
// negative or non-finite leave.
Cutter grown_cutter(const Cutter& cutter, double leave);

class CutterSpecError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// "flat:6", "ball:3.175", "bull:6:1", "ball:1/8in", "bull:0.25in:0.03in",
// "flat:6mm", "vbit:60:12.7", "vbit:90:0.5in:0.2", "taper:1:5:3.175",
// "taper:0.5:3.58:1/4in", "taper:1:7.16incl:6.35". Numbers may be decimals
// or fractions; a unit suffix (mm, in) applies to that number.
//   vbit:ANGLE:D[:TIP_W]    ANGLE the included angle (as V-bits are sold),
//                           D the top diameter, TIP_W the flat tip's width.
//   taper:TIP_D:ANGLE[:TOP_D]  TIP_D the ball tip's diameter, ANGLE the taper
//                           per side (as Fusion 360 and Vectric give it);
//                           TOP_D the diameter at the top of the flutes
//                           (default 3.175 mm, a 1/8 in shank).
// An angle may end in "incl" (included angle) or "side" (per side) to say
// which it is: vbit:30side:12.7 = vbit:60:12.7, taper:1:10incl = taper:1:5.
// A bull with corner radius 0 is a flat, with corner radius = R a ball.
Cutter parse_cutter_spec(std::string_view spec);

}  // namespace cncstream::cam
