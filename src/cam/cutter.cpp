#include "cncstream/cam/cutter.hpp"

#include <charconv>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace cncstream {

double Cutter::profile_height(double rho) const {
  const double rc = core_radius();
  if (rho <= rc) return 0.0;
  const double u = std::fmin(rho - rc, corner_radius);
  return corner_radius - std::sqrt(std::fmax(0.0, corner_radius * corner_radius - u * u));
}

Cutter Cutter::flat(double diameter) { return {CutterType::Flat, diameter / 2, 0.0}; }
Cutter Cutter::ball(double diameter) { return {CutterType::Ball, diameter / 2, diameter / 2}; }
Cutter Cutter::bull(double diameter, double corner_radius) {
  return {CutterType::Bull, diameter / 2, corner_radius};
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
  g.corner_radius = c.corner_radius + leave;
  g.type = c.type == CutterType::Ball ? CutterType::Ball : CutterType::Bull;
  return g;
}

std::string Cutter::spec() const {
  switch (type) {
    case CutterType::Flat: return "flat:" + fmt_num(diameter());
    case CutterType::Ball: return "ball:" + fmt_num(diameter());
    case CutterType::Bull: return "bull:" + fmt_num(diameter()) + ":" + fmt_num(corner_radius);
  }
  return {};
}

std::string Cutter::description() const {
  switch (type) {
    case CutterType::Flat: return fmt_num(diameter()) + " mm flat end mill";
    case CutterType::Ball: return fmt_num(diameter()) + " mm ball-nose end mill";
    case CutterType::Bull:
      return fmt_num(diameter()) + " mm bull-nose end mill, " + fmt_num(corner_radius) + " mm corner radius";
  }
  return {};
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

Cutter parse_cutter_spec(std::string_view spec) {
  std::vector<std::string_view> parts;
  std::size_t start = 0;
  for (;;) {
    const auto colon = spec.find(':', start);
    parts.push_back(spec.substr(start, colon == std::string_view::npos ? spec.npos : colon - start));
    if (colon == std::string_view::npos) break;
    start = colon + 1;
  }
  const std::string s(spec);
  const std::string usage = " (expected flat:D, ball:D or bull:D:r, e.g. flat:6, ball:3.175, bull:6:1, ball:1/8in)";
  if (parts.empty() || parts[0].empty()) throw CutterSpecError("empty cutter spec" + usage);
  const std::string_view kind = parts[0];
  if (kind == "flat" || kind == "ball") {
    if (parts.size() != 2) throw CutterSpecError("bad cutter spec '" + s + "': '" + std::string(kind) + "' takes one number, the diameter" + usage);
  } else if (kind == "bull") {
    if (parts.size() != 3) throw CutterSpecError("bad cutter spec '" + s + "': 'bull' takes the diameter and the corner radius" + usage);
  } else {
    throw CutterSpecError("bad cutter spec '" + s + "': unknown cutter type '" + std::string(kind) + "'" + usage);
  }
  const double d = parse_length(spec, parts[1], "diameter");
  if (!(d > 0)) throw CutterSpecError("bad cutter spec '" + s + "': diameter must be positive");
  if (d > 200) throw CutterSpecError("bad cutter spec '" + s + "': diameter " + fmt_num(d) + " mm is not plausible for a router bit");
  if (kind == "flat") return Cutter::flat(d);
  if (kind == "ball") return Cutter::ball(d);
  const double r = parse_length(spec, parts[2], "corner radius");
  if (r < 0) throw CutterSpecError("bad cutter spec '" + s + "': corner radius must not be negative");
  if (r > d / 2 * (1 + 1e-12))
    throw CutterSpecError("bad cutter spec '" + s + "': corner radius " + fmt_num(r) +
                          " mm exceeds the cutter radius " + fmt_num(d / 2) + " mm");
  if (r == 0) return Cutter::flat(d);
  if (r >= d / 2) return Cutter::ball(d);
  return Cutter::bull(d, r);
}

}  // namespace cncstream
