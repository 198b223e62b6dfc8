// Deviation maps: where the machined surface is below (gouge) or above
// (excess) the design, and by how much.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "cncstream/image/deviation_map.hpp"
#include "map_frame.hpp"

namespace cncstream::image {

namespace mf = map_frame;

namespace {

Rgb mix(Rgb a, Rgb b, double t) {
  t = std::clamp(t, 0.0, 1.0);
  auto ch = [&](double x, double y) { return static_cast<std::uint8_t>(std::lround(x + (y - x) * t)); };
  return {ch(a.r, b.r), ch(a.g, b.g), ch(a.b, b.b)};
}

}  // namespace

Rgb DeviationPalette::gouge(double severity) { return mix({250, 160, 140}, {150, 0, 20}, severity); }
Rgb DeviationPalette::excess(double severity) { return mix({160, 195, 240}, {15, 45, 140}, severity); }

Rgb DeviationScale::colour(double v) const {
  const double tol = tolerance;
  // Severity runs from the tolerance to the worst value of that sign.
  if (v < -tol) return DeviationPalette::gouge((-v - tol) / std::max(largest_gouge - tol, 1e-12));
  if (v > tol) return DeviationPalette::excess((v - tol) / std::max(largest_excess - tol, 1e-12));
  return DeviationPalette::within;
}

namespace {

constexpr int kLegendBarHeight = 240;

std::vector<std::string> legend_lines(const DeviationLegend& l) {
  const int dec = std::max(3, mf::decimals_for(l.tolerance) - 1);
  auto mm = [&](double v) { return mf::fixed(v, dec) + " mm"; };
  auto pct = [&](std::size_t n) { return mf::fixed(l.on_part ? 100.0 * n / l.on_part : 0, 1) + "%"; };
  // Appends, not "  " + s in a conditional: GCC 12 warns falsely (-Wrestrict).
  std::string lo_at, hi_at;
  if (l.lo < 0 && !l.lo_at.empty()) lo_at.append("  ").append(l.lo_at);
  if (l.hi > 0 && !l.hi_at.empty()) hi_at.append("  ").append(l.hi_at);
  return {
      "Machined - design",
      "gouge: below by > " + mm(l.tolerance),
      "within +/-" + mm(l.tolerance),
      "excess: above by > " + mm(l.tolerance),
      "off part (no design)",
      "largest gouge " + (l.lo < 0 ? mm(-l.lo) : std::string("none")),
      lo_at,
      "largest excess " + (l.hi > 0 ? mm(l.hi) : std::string("none")),
      hi_at,
      "gouged nodes " + std::to_string(l.gouged) + " (" + pct(l.gouged) + ")",
      "excess nodes " + std::to_string(l.excess) + " (" + pct(l.excess) + ")",
  };
}

}  // namespace

std::pair<int, int> deviation_legend_size(const DeviationLegend& l) {
  const int dec = std::max(3, mf::decimals_for(l.tolerance) - 1);
  const int w = std::max(mf::widest(legend_lines(l)) + 24,
                         48 + mf::widest({mf::fixed(l.lo, dec) + " mm", mf::fixed(l.hi, dec) + " mm"}));
  return {w, mf::kLineStep * 14 + kLegendBarHeight + 24};
}

void draw_deviation_legend(RgbImage& img, int x, int y, const DeviationLegend& l) {
  const double tol = l.tolerance;
  const std::vector<std::string> lines = legend_lines(l);
  const int dec = std::max(3, mf::decimals_for(tol) - 1);
  auto mm = [&](double v) { return mf::fixed(v, dec) + " mm"; };
  const DeviationScale scale{tol, -l.lo, l.hi};
  img.draw_text(x, y, lines[0], mf::kInk, mf::kTextScale);
  y += mf::kLineStep + 4;
  mf::draw_swatch(img, x, y, DeviationPalette::gouge(0.6), lines[1]);
  y += mf::kLineStep;
  mf::draw_swatch(img, x, y, DeviationPalette::within, lines[2]);
  y += mf::kLineStep;
  mf::draw_swatch(img, x, y, DeviationPalette::excess(0.6), lines[3]);
  y += mf::kLineStep;
  mf::draw_swatch(img, x, y, DeviationPalette::off_part, lines[4]);
  y += mf::kLineStep + 12;

  // The colour bar spans the data's range (at least the tolerance band).
  const double blo = std::min(l.lo, -2 * tol), bhi = std::max(l.hi, 2 * tol);
  auto t_of = [&](double v) { return (v - blo) / (bhi - blo); };
  std::vector<std::pair<double, std::string>> labels = {{1.0, mm(bhi)}, {t_of(tol), std::string("+").append(mm(tol))},
                                                        {t_of(-tol), mm(-tol)}, {0.0, mm(blo)}};
  mf::draw_colour_bar(img, x, y, 24, kLegendBarHeight, [&](double t) { return scale.colour(blo + t * (bhi - blo)); },
                      labels);
  y += kLegendBarHeight + 16;
  for (std::size_t q = 5; q < lines.size(); ++q) {
    if (lines[q].empty()) continue;
    img.draw_text(x, y, lines[q], q >= 9 ? mf::kFaint : mf::kInk, mf::kTextScale);
    y += mf::kLineStep;
  }
}

RgbImage render_deviation_map(const MapGrid& grid, std::span<const double> dev, std::span<const std::uint8_t> off,
                              const DeviationMapOptions& options) {
  if (grid.size() == 0) throw std::invalid_argument("deviation map: the grid is empty");
  if (dev.size() != grid.size())
    throw std::invalid_argument("deviation map: " + std::to_string(dev.size()) + " values for a grid of " +
                                std::to_string(grid.size()) + " nodes");
  if (!off.empty() && off.size() != grid.size())
    throw std::invalid_argument("deviation map: off-part mask has " + std::to_string(off.size()) +
                                " entries for a grid of " + std::to_string(grid.size()) + " nodes");
  const double tol = options.tolerance;
  if (!(tol > 0) || !std::isfinite(tol)) throw std::invalid_argument("deviation map: tolerance must be positive");

  auto on_part = [&](std::size_t k) { return (off.empty() || !off[k]) && std::isfinite(dev[k]); };
  double lo = 0, hi = 0;  // most negative and most positive deviation
  std::size_t klo = 0, khi = 0, gouged = 0, excess = 0, on = 0;
  for (std::size_t k = 0; k < dev.size(); ++k) {
    if (!on_part(k)) continue;
    ++on;
    if (dev[k] < lo) lo = dev[k], klo = k;
    if (dev[k] > hi) hi = dev[k], khi = k;
    gouged += dev[k] < -tol;
    excess += dev[k] > tol;
  }
  const DeviationScale scale{tol, -lo, hi};
  auto colour_of = [&](double v) { return scale.colour(v); };

  DeviationLegend legend{tol, lo, hi, "", "", gouged, excess, on};
  auto at = [&](std::size_t k) {
    const std::size_t i = k % grid.nx, j = k / grid.nx;
    return "at x " + mf::fixed(grid.x0 + i * grid.dx, 2) + " y " + mf::fixed(grid.y0 + j * grid.dy, 2);
  };
  if (lo < 0) legend.lo_at = at(klo);
  if (hi > 0) legend.hi_at = at(khi);
  const auto [legend_w, legend_h] = deviation_legend_size(legend);
  mf::Frame f = mf::make_frame(grid, options.max_map_pixels, options.title, options.subtitle, legend_w, legend_h);
  RgbImage& img = f.image;

  // Each pixel shows the worst node it covers: the deepest gouge beyond the
  // tolerance if any, else the largest deviation of either sign.
  for (int py = 0; py < f.map_h; ++py)
    for (int px = 0; px < f.map_w; ++px) {
      const auto r = mf::nodes_under(f, grid, px, py);
      bool any = false;
      double worst = 0;
      for (std::size_t j = r.j0; j <= r.j1; ++j)
        for (std::size_t i = r.i0; i <= r.i1; ++i) {
          const std::size_t k = j * grid.nx + i;
          if (!on_part(k)) continue;
          const double v = dev[k];
          const bool v_gouge = v < -tol, w_gouge = worst < -tol;
          if (!any || (v_gouge && (!w_gouge || v < worst)) || (!w_gouge && !v_gouge && std::fabs(v) > std::fabs(worst)))
            worst = v;
          any = true;
        }
      f.image.set(f.map_x + px, f.map_y + py, any ? colour_of(worst) : DeviationPalette::off_part);
    }

  draw_deviation_legend(img, f.legend_x, f.legend_y, legend);
  return std::move(f.image);
}

}  // namespace cncstream::image
