#include "cncstream/cam/cutter.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace cncstream::cam {

double Cutter::profile_height(double rho) const {
  if (!is_apt()) return profile().h(rho);
  const double rc = core_radius();
  if (rho <= rc) return 0.0;
  const double u = std::fmin(rho - rc, corner_radius);
  return corner_radius - std::sqrt(std::fmax(0.0, corner_radius * corner_radius - u * u));
}

double Cutter::profile_top() const { return is_apt() ? corner_radius : profile().top; }

namespace detail_cutter_profile {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

ProfileBand cone(double rho0, double rho1, double h0, double slope) {
  ProfileBand b;
  b.kind = ProfileBand::Kind::Cone;
  b.rho0 = rho0;
  b.rho1 = rho1;
  b.h0 = h0;
  b.slope = slope;
  b.sin0 = b.sin1 = slope / std::sqrt(1 + slope * slope);
  return b;
}

// The arc of the circle (a, zc, r) between the tilt sines s0 and s1.
ProfileBand arc(double a, double zc, double r, double s0, double s1) {
  ProfileBand b;
  b.kind = ProfileBand::Kind::Arc;
  b.a = a;
  b.zc = zc;
  b.r = r;
  b.sin0 = s0;
  b.sin1 = s1;
  b.rho0 = a + r * s0;
  b.rho1 = a + r * s1;
  b.h0 = zc - r * std::sqrt(std::fmax(0.0, (1 - s0) * (1 + s0)));
  return b;
}

// The profile offset by g along its outward normals (Minkowski sum with a
// ball of radius g, heights measured from the new tip g lower): bands move
// out along their normals, and every corner (the pointed tip, a kink, the
// rim where the wall begins) becomes an arc of radius g about it.
CutterProfile offset(const CutterProfile& p, double g) {
  if (!(g > 0)) return p;
  CutterProfile out;
  auto add = [&](const ProfileBand& b) {
    if (b.rho1 > b.rho0 && out.count < CutterProfile::kMaxBands) out.band[out.count++] = b;
  };
  double prev_sin = 0, prev_rho = 0, prev_h = 0;
  for (std::size_t k = 0; k < p.count; ++k) {
    const ProfileBand& b = p.band[k];
    if (b.sin0 > prev_sin + 1e-12) add(arc(prev_rho, prev_h + g, g, prev_sin, b.sin0));
    if (b.kind == ProfileBand::Kind::Cone) {
      const double c = std::sqrt((1 - b.sin0) * (1 + b.sin0));
      ProfileBand m = cone(b.rho0 + g * b.sin0, b.rho1 + g * b.sin0, b.h0 + g * (1 - c), b.slope);
      add(m);
    } else {
      add(arc(b.a, b.zc + g, b.r + g, b.sin0, b.sin1));
    }
    prev_sin = b.sin1;
    prev_rho = b.rho1;
    prev_h = b.h(b.rho1);
  }
  if (prev_sin < 1 - 1e-12) add(arc(prev_rho, prev_h + g, g, prev_sin, 1.0));
  const ProfileBand& last = out.band[out.count - 1];
  out.R = last.rho1;
  // (An arc up to the vertical ends at its centre's height: no rounding.)
  out.top = last.kind == ProfileBand::Kind::Arc && last.sin1 >= 1 ? last.zc : last.h(out.R);
  return out;
}

}  // namespace detail_cutter_profile

CutterProfile Cutter::profile() const {
  using namespace detail_cutter_profile;
  CutterProfile p;
  auto add = [&](const ProfileBand& b) {
    if (b.rho1 > b.rho0) p.band[p.count++] = b;
  };
  const double R = radius;
  if (!(R > 0) || !std::isfinite(R)) throw std::invalid_argument("cutter radius must be positive and finite");
  switch (type) {
    case CutterType::Flat: add(cone(0, R, 0, 0)); break;
    case CutterType::Ball: add(arc(0, R, R, 0, 1)); break;
    case CutterType::Bull: {
      const double rk = std::clamp(corner_radius, 0.0, R);
      add(cone(0, R - rk, 0, 0));
      if (rk > 0) add(arc(R - rk, rk, rk, 0, 1));
      break;
    }
    case CutterType::VBit:
    case CutterType::TaperedBall: {
      const double alpha = half_angle_deg * kDeg;
      if (!(alpha > 0 && alpha < 90 * kDeg))
        throw std::invalid_argument("cutter cone angle must lie strictly between 0 and 90 degrees per side");
      const double slope = 1 / std::tan(alpha), ca = std::cos(alpha);
      const double Rb = R - grown;  // the cutter before growing
      if (type == CutterType::VBit) {
        if (!(tip_radius >= 0 && tip_radius < Rb)) throw std::invalid_argument("V-bit tip must be narrower than the cutter");
        add(cone(0, tip_radius, 0, 0));
        add(cone(tip_radius, Rb, 0, slope));
      } else {
        const double r = corner_radius;
        if (!(r > 0 && r * ca < Rb)) throw std::invalid_argument("tapered ball: the ball must be narrower than the top");
        add(arc(0, r, r, 0, ca));
        add(cone(r * ca, Rb, r * (1 - std::sin(alpha)), slope));
      }
      p.R = Rb;
      p.top = p.band[p.count - 1].h(Rb);
      if (grown > 0) p = offset(p, grown);
      return p;
    }
  }
  p.R = R;
  p.top = p.band[p.count - 1].h(R);
  return p;
}

Cutter Cutter::flat(double diameter) { return {CutterType::Flat, diameter / 2, 0.0}; }
Cutter Cutter::ball(double diameter) { return {CutterType::Ball, diameter / 2, diameter / 2}; }
Cutter Cutter::bull(double diameter, double corner_radius) {
  return {CutterType::Bull, diameter / 2, corner_radius};
}
Cutter Cutter::vbit(double included_angle_deg, double diameter, double tip_width) {
  Cutter c{CutterType::VBit, diameter / 2, 0.0};
  c.half_angle_deg = included_angle_deg / 2;
  c.tip_radius = tip_width / 2;
  return c;
}
Cutter Cutter::tapered_ball(double tip_diameter, double half_angle_deg, double top_diameter) {
  Cutter c{CutterType::TaperedBall, top_diameter / 2, tip_diameter / 2};
  c.half_angle_deg = half_angle_deg;
  return c;
}

namespace {
std::string fmt_num(double v) {
  std::ostringstream o;
  o.precision(10);
  o << v;
  return o.str();
}
}  // namespace

Cutter grown_cutter(const Cutter& c, double leave) {
  if (!(leave >= 0) || !std::isfinite(leave))
    throw std::invalid_argument("stock to leave must be a finite length >= 0, got " + fmt_num(leave));
  if (leave == 0) return c;
  Cutter g = c;
  g.radius = c.radius + leave;
  if (!c.is_apt()) {
    g.grown = c.grown + leave;
    return g;
  }
  g.corner_radius = c.corner_radius + leave;
  g.type = c.type == CutterType::Ball ? CutterType::Ball : CutterType::Bull;
  return g;
}

std::string Cutter::spec() const {
  switch (type) {
    case CutterType::Flat: return "flat:" + fmt_num(diameter());
    case CutterType::Ball: return "ball:" + fmt_num(diameter());
    case CutterType::Bull: return "bull:" + fmt_num(diameter()) + ":" + fmt_num(corner_radius);
    case CutterType::VBit: {
      // (A grown cutter has no spec of its own: the cutter it was grown from.)
      std::string s = "vbit:" + fmt_num(2 * half_angle_deg) + ":" + fmt_num(2 * (radius - grown));
      if (tip_radius > 0) s += ":" + fmt_num(2 * tip_radius);
      return s;
    }
    case CutterType::TaperedBall:
      return "taper:" + fmt_num(2 * corner_radius) + ":" + fmt_num(half_angle_deg) + ":" + fmt_num(2 * (radius - grown));
  }
  return {};
}

std::string Cutter::description() const {
  std::string d;
  switch (type) {
    case CutterType::Flat: return fmt_num(diameter()) + " mm flat end mill";
    case CutterType::Ball: return fmt_num(diameter()) + " mm ball-nose end mill";
    case CutterType::Bull:
      return fmt_num(diameter()) + " mm bull-nose end mill, " + fmt_num(corner_radius) + " mm corner radius";
    case CutterType::VBit:
      d = fmt_num(2 * (radius - grown)) + " mm " + fmt_num(2 * half_angle_deg) + "\u00b0 V-bit";
      if (tip_radius > 0) d += ", " + fmt_num(2 * tip_radius) + " mm flat tip";
      break;
    case CutterType::TaperedBall:
      d = fmt_num(2 * corner_radius) + " mm tapered ball-nose, " + fmt_num(half_angle_deg) + "\u00b0 per side, " +
          fmt_num(2 * (radius - grown)) + " mm at the top";
      break;
  }
  if (grown > 0) d += ", grown by " + fmt_num(grown) + " mm";
  return d;
}

namespace {

// "6", "3.175", "1/8", "0.25in", "1/8in", "6mm"
double parse_length(std::string_view full, std::string_view s, const char* what) {
  auto bad = [&](const std::string& why) -> CutterSpecError {
    return CutterSpecError("bad cutter spec '" + std::string(full) + "': " + what + " '" + std::string(s) +
                           "' " + why);
  };
  double unit = 1.0;
  if (s.size() > 2 && s.substr(s.size() - 2) == "in") {
    unit = 25.4;
    s.remove_suffix(2);
  } else if (s.size() > 2 && s.substr(s.size() - 2) == "mm") {
    s.remove_suffix(2);
  } else if (s.size() > 1 && s.back() == '"') {
    unit = 25.4;
    s.remove_suffix(1);
  }
  auto num = [&](std::string_view t) {
    double v = 0;
    auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (t.empty() || ec != std::errc() || p != t.data() + t.size() || !std::isfinite(v))
      throw bad("is not a number");
    return v;
  };
  double v;
  if (auto slash = s.find('/'); slash != std::string_view::npos) {
    const double a = num(s.substr(0, slash)), b = num(s.substr(slash + 1));
    if (b == 0) throw bad("divides by zero");
    v = a / b;
  } else {
    v = num(s);
  }
  return v * unit;
}

}  // namespace

namespace detail_cutter_spec {

enum class AngleKind { Unsaid, Included, PerSide };

// "60", "7.16incl", "30side", "5deg": degrees, with what the angle measures.
double parse_angle(std::string_view full, std::string_view s, AngleKind& kind) {
  kind = AngleKind::Unsaid;
  auto strip = [&](std::string_view suffix) {
    if (s.size() > suffix.size() && s.substr(s.size() - suffix.size()) == suffix) {
      s.remove_suffix(suffix.size());
      return true;
    }
    return false;
  };
  if (strip("incl")) kind = AngleKind::Included;
  else if (strip("side")) kind = AngleKind::PerSide;
  strip("deg");
  double v = 0;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || p != s.data() + s.size() || !std::isfinite(v))
    throw CutterSpecError("bad cutter spec '" + std::string(full) + "': angle '" + std::string(s) +
                          "' is not a number of degrees (e.g. 60, 5, 10incl, 5side)");
  return v;
}

}  // namespace detail_cutter_spec

Cutter parse_cutter_spec(std::string_view spec) {
  using detail_cutter_spec::AngleKind;
  std::vector<std::string_view> parts;
  std::size_t start = 0;
  for (;;) {
    const auto colon = spec.find(':', start);
    parts.push_back(spec.substr(start, colon == std::string_view::npos ? spec.npos : colon - start));
    if (colon == std::string_view::npos) break;
    start = colon + 1;
  }
  const std::string s(spec);
  const std::string usage =
      " (expected flat:D, ball:D, bull:D:r, vbit:ANGLE:D[:TIP_W] or taper:TIP_D:ANGLE[:TOP_D], e.g. flat:6, ball:3.175, "
      "bull:6:1, ball:1/8in, vbit:60:12.7, taper:1:5:3.175)";
  auto bad = [&](const std::string& why) { return CutterSpecError("bad cutter spec '" + s + "': " + why); };
  if (parts.empty() || parts[0].empty()) throw CutterSpecError("empty cutter spec" + usage);
  const std::string_view kind = parts[0];
  if (kind == "flat" || kind == "ball") {
    if (parts.size() != 2) throw bad("'" + std::string(kind) + "' takes one number, the diameter" + usage);
  } else if (kind == "bull") {
    if (parts.size() != 3) throw bad("'bull' takes the diameter and the corner radius" + usage);
  } else if (kind == "vbit") {
    if (parts.size() != 3 && parts.size() != 4)
      throw bad("'vbit' takes the included angle, the top diameter and optionally the flat tip's width" + usage);
  } else if (kind == "taper") {
    if (parts.size() != 3 && parts.size() != 4)
      throw bad("'taper' takes the ball tip's diameter, the taper angle per side and optionally the top diameter" + usage);
  } else {
    throw bad("unknown cutter type '" + std::string(kind) + "'" + usage);
  }
  auto plausible_diameter = [&](double d, const char* what) {
    if (!(d > 0)) throw bad(std::string(what) + " must be positive");
    if (d > 200) throw bad(std::string(what) + " " + fmt_num(d) + " mm is not plausible for a router bit");
  };
  if (kind == "vbit") {
    AngleKind ak;
    double angle = detail_cutter_spec::parse_angle(spec, parts[1], ak);
    if (ak == AngleKind::PerSide) angle *= 2;
    if (!(angle > 0 && angle < 180))
      throw bad("included angle " + fmt_num(angle) + " degrees must lie strictly between 0 and 180");
    const double d = parse_length(spec, parts[2], "diameter");
    plausible_diameter(d, "diameter");
    const double tip = parts.size() == 4 ? parse_length(spec, parts[3], "tip width") : 0.0;
    if (!(tip >= 0)) throw bad("tip width must not be negative");
    if (!(tip < d)) throw bad("tip width " + fmt_num(tip) + " mm must be less than the diameter " + fmt_num(d) + " mm");
    return Cutter::vbit(angle, d, tip);
  }
  if (kind == "taper") {
    const double tip = parse_length(spec, parts[1], "tip diameter");
    plausible_diameter(tip, "tip diameter");
    AngleKind ak;
    double angle = detail_cutter_spec::parse_angle(spec, parts[2], ak);
    if (ak == AngleKind::Included) angle /= 2;
    if (!(angle > 0 && angle < 90))
      throw bad("taper angle " + fmt_num(angle) + " degrees per side must lie strictly between 0 and 90");
    const double top = parts.size() == 4 ? parse_length(spec, parts[3], "top diameter") : 3.175;
    plausible_diameter(top, "top diameter");
    if (!(top > tip))
      throw bad("top diameter " + fmt_num(top) + " mm must exceed the tip diameter " + fmt_num(tip) + " mm" +
                (parts.size() == 4 ? "" : " (give the top of the flutes: taper:TIP_D:ANGLE:TOP_D)"));
    return Cutter::tapered_ball(tip, angle, top);
  }
  const double d = parse_length(spec, parts[1], "diameter");
  plausible_diameter(d, "diameter");
  if (kind == "flat") return Cutter::flat(d);
  if (kind == "ball") return Cutter::ball(d);
  const double r = parse_length(spec, parts[2], "corner radius");
  if (r < 0) throw bad("corner radius must not be negative");
  if (r > d / 2 * (1 + 1e-12))
    throw bad("corner radius " + fmt_num(r) + " mm exceeds the cutter radius " + fmt_num(d / 2) + " mm");
  if (r == 0) return Cutter::flat(d);
  if (r >= d / 2) return Cutter::ball(d);
  return Cutter::bull(d, r);
}

}  // namespace cncstream::cam
