#include "cncstream/cam/cutter_selection.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace cncstream::cam {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}

double d_base(RemovalCriterion criterion, double rc, double rk) {
  if (!(rc > 0) || !(rk > 0)) throw std::invalid_argument("d_base needs a core radius and a corner radius above 0");
  const double R = rc + rk;
  if (criterion == RemovalCriterion::Volume)
    return ((2 * M_PI / 3) * R * R * R - M_PI * rc * rc * rk - (2 * M_PI / 3) * rk * rk * rk -
            (M_PI * M_PI / 2) * rc * rk * rk) /
           (M_PI * R * R);
  return ((M_PI / 4) * R * R - rc * rk - (M_PI / 4) * rk * rk) / R;
}

double inclined_plane_d(double rc, double alpha) { return rc * (1 - std::sin(alpha)) / std::cos(alpha); }

double switch_angle(double rc, double dbase) {
  // (1 - sin a) / cos a = (1 - t) / (1 + t) with t = tan(a / 2).
  const double q = std::clamp(dbase / rc, 0.0, 1.0);
  return 2 * std::atan((1 - q) / (1 + q));
}

CutterPair::CutterPair(Cutter b, Cutter r) : ball(b), radiused(r) {
  if (ball.type != CutterType::Ball) throw std::invalid_argument("cutter selection: '" + ball.spec() + "' is not a ball-nose cutter");
  if (radiused.type != CutterType::Bull)
    throw std::invalid_argument("cutter selection: '" + radiused.spec() + "' is not a radiused (bull-nose) cutter");
  if (std::fabs(ball.radius - radiused.radius) > 1e-9 * (1 + ball.radius))
    throw std::invalid_argument("cutter selection compares cutters of one diameter: '" + ball.spec() + "' and '" +
                                radiused.spec() + "' differ");
}

RemovalChoice choose_by_removal(const CutterPair& c, const ClGrid& ball, const ClGrid& rad) {
  const GridSpec& g = ball.spec;
  if (g.nx != rad.spec.nx || g.ny != rad.spec.ny || g.x0 != rad.spec.x0 || g.y0 != rad.spec.y0 || g.dx != rad.spec.dx ||
      g.dy != rad.spec.dy)
    throw std::invalid_argument("cutter selection: the two CL grids differ");
  RemovalChoice out;
  out.grid = g;
  out.d_base_volume = d_base(RemovalCriterion::Volume, c.rc(), c.rk());
  out.d_base_area = d_base(RemovalCriterion::Area, c.rc(), c.rk());
  const std::size_t n = g.size();
  out.d.assign(n, kNaN);
  out.slope_deg.assign(n, kNaN);
  out.by_volume.assign(n, Choice::None);
  out.by_area.assign(n, Choice::None);
  const double R = c.ball.radius, rk = c.rk();
  auto off = [&](std::size_t k) { return ball.on_floor[k] || rad.on_floor[k]; };
  for (std::size_t j = 0; j < g.ny; ++j) {
    for (std::size_t i = 0; i < g.nx; ++i) {
      const std::size_t k = j * g.nx + i;
      if (off(k)) continue;
      const double d = (ball.z[k] + R) - (rad.z[k] + rk);
      out.d[k] = d;
      out.by_volume[k] = d > out.d_base_volume ? Choice::Radiused : Choice::Ball;
      out.by_area[k] = d > out.d_base_area ? Choice::Radiused : Choice::Ball;
      ++out.on_part;
      out.radiused_by_volume += out.by_volume[k] == Choice::Radiused;
      out.radiused_by_area += out.by_area[k] == Choice::Radiused;
      // The ball's centre surface is the design offset by R: its normal is
      // the design's normal at the contact, so its gradient gives the slope.
      auto z_at = [&](std::size_t ii, std::size_t jj) { return ball.z[jj * g.nx + ii]; };
      const std::size_t i0 = i > 0 ? i - 1 : i, i1 = i + 1 < g.nx ? i + 1 : i;
      const std::size_t j0 = j > 0 ? j - 1 : j, j1 = j + 1 < g.ny ? j + 1 : j;
      if (i1 == i0 || j1 == j0) continue;
      const double gx = (z_at(i1, j) - z_at(i0, j)) / (double(i1 - i0) * g.dx);
      const double gy = (z_at(i, j1) - z_at(i, j0)) / (double(j1 - j0) * g.dy);
      out.slope_deg[k] = std::atan(std::sqrt(gx * gx + gy * gy)) * 180 / M_PI;
    }
  }
  return out;
}

SlopeProfile slope_profile(const RemovalChoice& c, double bin_deg) {
  if (!(bin_deg > 0)) throw std::invalid_argument("slope bin width must be positive");
  SlopeProfile p;
  const std::size_t nbins = static_cast<std::size_t>(std::ceil(90 / bin_deg));
  for (std::size_t b = 0; b < nbins; ++b) p.bins.push_back({double(b) * bin_deg, std::min(90.0, double(b + 1) * bin_deg)});
  for (std::size_t k = 0; k < c.slope_deg.size(); ++k) {
    const double s = c.slope_deg[k];
    if (!std::isfinite(s) || c.by_volume[k] == Choice::None) continue;
    const std::size_t b = std::min(nbins - 1, static_cast<std::size_t>(s / bin_deg));
    ++p.bins[b].nodes;
    p.bins[b].radiused_by_volume += c.by_volume[k] == Choice::Radiused;
    p.bins[b].radiused_by_area += c.by_area[k] == Choice::Radiused;
  }
  // A bin counts once it holds a meaningful sample of the part.
  const std::size_t min_nodes = std::max<std::size_t>(20, c.on_part / 2000);
  // The slope where the radiused share crosses one half: linear between the
  // centres of the last radiused-majority bin and the first ball-majority bin.
  auto first_ball_bin = [&](auto radiused_of) {
    double prev_centre = kNaN, prev_share = kNaN;
    for (const auto& b : p.bins) {
      if (b.nodes < min_nodes) continue;
      const double centre = 0.5 * (b.lo_deg + b.hi_deg);
      const double share = double(radiused_of(b)) / double(b.nodes);
      if (share < 0.5) {
        if (!std::isfinite(prev_share) || prev_share == share) return centre;
        return prev_centre + (centre - prev_centre) * (prev_share - 0.5) / (prev_share - share);
      }
      prev_centre = centre;
      prev_share = share;
    }
    return kNaN;
  };
  p.switch_deg_volume = first_ball_bin([](const SlopeBin& b) { return b.radiused_by_volume; });
  p.switch_deg_area = first_ball_bin([](const SlopeBin& b) { return b.radiused_by_area; });
  return p;
}

double scallop_2d(const Cutter& cutter, double s, double slope) {
  if (!(s > 0)) throw std::invalid_argument("stepover must be positive");
  const double R = cutter.radius, t = std::tan(slope);
  // Cross-section of the cutter across the passes: f(u) = profile height at
  // |u|. Over the line z = t*y, a pass at y_k leaves f(y - y_k) - t*(y - y_k)
  // + c above the line, c chosen so its lowest point touches the line.
  auto rel = [&](double u) { return std::fabs(u) > R ? HUGE_VAL : cutter.profile_height(std::fabs(u)) - t * u; };
  constexpr int kSamples = 2000;
  double touch = HUGE_VAL, u_touch = 0;
  for (int k = 0; k <= kSamples; ++k) {
    const double u = -R + 2 * R * k / kSamples, v = rel(u);
    if (v < touch) {
      touch = v;
      u_touch = u;
    }
  }
  // The cusp lies between the two passes' contact points.
  double cusp = 0;
  for (int k = 0; k <= kSamples; ++k) {
    const double y = u_touch + s * k / kSamples;
    cusp = std::max(cusp, std::min(rel(y), rel(y - s)) - touch);
  }
  // Passes farther apart than the cutter reaches leave the surface uncut.
  return std::isfinite(cusp) ? cusp : HUGE_VAL;
}

}  // namespace cncstream::cam
