// Shaded-relief height maps.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "cncstream/image/height_map.hpp"
#include "map_frame.hpp"

namespace cncstream::image {

namespace mf = map_frame;

namespace {

constexpr Rgb kNoData{205, 205, 205};

struct Shaded {
  std::vector<float> rgb;  // per node, 0..255
  std::vector<std::uint8_t> ok;
};

// Colour by height times a Lambert shade from the light; the shade is scaled
// so a level surface keeps its true ramp colour.
Shaded shade_nodes(const MapGrid& g, std::span<const double> z, std::span<const std::uint8_t> invalid, double zlo,
                   double zhi, const HeightMapOptions& o) {
  const double az = o.light_azimuth_deg * std::numbers::pi / 180, el = o.light_elevation_deg * std::numbers::pi / 180;
  const double lx = std::cos(el) * std::sin(az), ly = std::cos(el) * std::cos(az), lz = std::sin(el);
  const double level = std::max(lz, 0.05);
  Shaded s;
  s.rgb.assign(g.size() * 3, 0);
  s.ok.assign(g.size(), 0);
  auto valid = [&](std::size_t i, std::size_t j) {
    const std::size_t k = j * g.nx + i;
    return (invalid.empty() || !invalid[k]) && std::isfinite(z[k]);
  };
  // Slope along one axis from whichever neighbours have values.
  auto slope = [&](std::size_t i, std::size_t j, bool along_x) {
    const std::size_t n = along_x ? g.nx : g.ny, c = along_x ? i : j;
    const double step = along_x ? g.dx : g.dy;
    auto zz = [&](std::size_t t) { return along_x ? z[j * g.nx + t] : z[t * g.nx + i]; };
    auto ok = [&](std::size_t t) { return along_x ? valid(t, j) : valid(i, t); };
    const bool lo = c > 0 && ok(c - 1), hi = c + 1 < n && ok(c + 1);
    if (lo && hi) return (zz(c + 1) - zz(c - 1)) / (2 * step);
    if (hi) return (zz(c + 1) - zz(c)) / step;
    if (lo) return (zz(c) - zz(c - 1)) / step;
    return 0.0;
  };
  const double span = zhi > zlo ? zhi - zlo : 1.0;
  for (std::size_t j = 0; j < g.ny; ++j)
    for (std::size_t i = 0; i < g.nx; ++i) {
      if (!valid(i, j)) continue;
      const std::size_t k = j * g.nx + i;
      const double gx = slope(i, j, true) * o.vertical_exaggeration, gy = slope(i, j, false) * o.vertical_exaggeration;
      const double shade = std::max(0.0, (-gx * lx - gy * ly + lz) / std::sqrt(gx * gx + gy * gy + 1));
      const double factor = std::clamp(0.3 + 0.7 * shade / level, 0.15, 1.25);
      const Rgb c = colormap_viridis(zhi > zlo ? (z[k] - zlo) / span : 0.5);
      s.rgb[3 * k] = static_cast<float>(std::min(255.0, c.r * factor));
      s.rgb[3 * k + 1] = static_cast<float>(std::min(255.0, c.g * factor));
      s.rgb[3 * k + 2] = static_cast<float>(std::min(255.0, c.b * factor));
      s.ok[k] = 1;
    }
  return s;
}

// Bilinear blend of the valid nodes around a pixel; no-data where the
// nearest node has no value (so holes keep their true outline).
Rgb sample(const Shaded& s, const MapGrid& g, const mf::Frame& f, int px, int py) {
  const auto [ni, nj] = mf::node_at(f, g, px, py);
  if (!s.ok[nj * g.nx + ni]) return kNoData;
  const auto [u, v] = mf::node_coords(f, g, px, py);
  const double fu = std::clamp(u, 0.0, static_cast<double>(g.nx - 1)), fv = std::clamp(v, 0.0, static_cast<double>(g.ny - 1));
  const std::size_t i0 = static_cast<std::size_t>(fu), j0 = static_cast<std::size_t>(fv);
  const std::size_t i1 = std::min(i0 + 1, g.nx - 1), j1 = std::min(j0 + 1, g.ny - 1);
  const double a = fu - i0, b = fv - j0;
  double acc[3] = {0, 0, 0}, wsum = 0;
  const std::size_t is[2] = {i0, i1}, js[2] = {j0, j1};
  const double wi[2] = {1 - a, a}, wj[2] = {1 - b, b};
  for (int q = 0; q < 2; ++q)
    for (int p = 0; p < 2; ++p) {
      const std::size_t k = js[q] * g.nx + is[p];
      const double w = wi[p] * wj[q];
      if (!s.ok[k] || w <= 0) continue;
      for (int c = 0; c < 3; ++c) acc[c] += w * s.rgb[3 * k + c];
      wsum += w;
    }
  if (wsum <= 0) return kNoData;
  auto ch = [&](int c) { return static_cast<std::uint8_t>(std::lround(std::clamp(acc[c] / wsum, 0.0, 255.0))); };
  return {ch(0), ch(1), ch(2)};
}

}  // namespace

RgbImage render_height_map(const MapGrid& grid, std::span<const double> values,
                           std::span<const std::uint8_t> invalid, const HeightMapOptions& options) {
  if (grid.size() == 0) throw std::invalid_argument("height map: the grid is empty");
  if (values.size() != grid.size())
    throw std::invalid_argument("height map: " + std::to_string(values.size()) + " values for a grid of " +
                                std::to_string(grid.size()) + " nodes");
  if (!invalid.empty() && invalid.size() != grid.size())
    throw std::invalid_argument("height map: invalid-node mask has " + std::to_string(invalid.size()) +
                                " entries for a grid of " + std::to_string(grid.size()) + " nodes");
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  std::size_t nvalid = 0;
  for (std::size_t k = 0; k < values.size(); ++k)
    if ((invalid.empty() || !invalid[k]) && std::isfinite(values[k])) {
      lo = std::min(lo, values[k]);
      hi = std::max(hi, values[k]);
      ++nvalid;
    }
  if (options.z_min) lo = *options.z_min;
  if (options.z_max) hi = *options.z_max;
  if (nvalid == 0 && !(options.z_min && options.z_max)) lo = hi = 0;
  if (hi < lo) throw std::invalid_argument("height map: colour range max is below min");

  const int dec = mf::decimals_for(hi - lo);
  const std::vector<std::string> lines = {"Height (mm)", mf::fixed(hi, dec) + " mm", mf::fixed(lo, dec) + " mm",
                                          "no data", "light from " + mf::fixed(options.light_azimuth_deg, 0) + " deg"};
  const int bar_h = 260;
  const int legend_w = 48 + mf::widest(lines);
  const int legend_h = mf::kLineStep + bar_h + 16 + 3 * mf::kLineStep;
  mf::Frame f = mf::make_frame(grid, options.max_map_pixels, options.title, options.subtitle, legend_w, legend_h);

  const Shaded s = shade_nodes(grid, values, invalid, lo, hi, options);
  for (int py = 0; py < f.map_h; ++py)
    for (int px = 0; px < f.map_w; ++px) f.image.set(f.map_x + px, f.map_y + py, sample(s, grid, f, px, py));

  // Legend: the ramp with its extremes and three steps between, unshaded.
  RgbImage& img = f.image;
  int y = f.legend_y;
  img.draw_text(f.legend_x, y, lines[0], mf::kInk, mf::kTextScale);
  y += mf::kLineStep + 8;
  std::vector<std::pair<double, std::string>> labels;
  for (int q = 0; q <= 4; ++q) {
    const double t = q / 4.0;
    labels.emplace_back(t, mf::fixed(lo + t * (hi - lo), dec) + (q == 0 || q == 4 ? " mm" : ""));
  }
  if (!(hi > lo)) labels = {{0.5, mf::fixed(lo, dec) + " mm"}};
  mf::draw_colour_bar(img, f.legend_x, y, 24, bar_h, [](double t) { return colormap_viridis(t); }, labels);
  y += bar_h + 16;
  if (nvalid < grid.size()) {
    mf::draw_swatch(img, f.legend_x, y, kNoData, "no data");
    y += mf::kLineStep;
  }
  img.draw_text(f.legend_x, y, lines[4], mf::kFaint, mf::kTextScale);
  return std::move(f.image);
}

RgbImage render_height_image(const MapGrid& grid, std::span<const float> values, const HeightImageOptions& o) {
  if (grid.size() == 0) throw std::invalid_argument("height image: the grid is empty");
  if (values.size() != grid.size())
    throw std::invalid_argument("height image: " + std::to_string(values.size()) + " values for a grid of " +
                                std::to_string(grid.size()) + " nodes");
  if (o.width < 1 || o.height < 1 || o.width > 8000 || o.height > 8000)
    throw std::invalid_argument("height image: size " + std::to_string(o.width) + "x" + std::to_string(o.height) +
                                " is outside 1..8000");
  RgbImage img(o.width, o.height, o.no_data);
  const double span = o.z_max > o.z_min ? o.z_max - o.z_min : 0;
  const auto z_at = [&](std::size_t i, std::size_t j) { return values[j * grid.nx + i]; };
  for (int py = 0; py < o.height; ++py) {
    // Pixel centres spread over the node range [0, n-1]; row 0 is the north edge.
    const double v = grid.ny > 1 ? (o.height - py - 0.5) / o.height * double(grid.ny - 1) : 0;
    const std::size_t j0 = std::min(static_cast<std::size_t>(v), grid.ny - 1), j1 = std::min(j0 + 1, grid.ny - 1);
    const double b = v - double(j0);
    const std::size_t jn = b < 0.5 ? j0 : j1;
    for (int px = 0; px < o.width; ++px) {
      const double u = grid.nx > 1 ? (px + 0.5) / o.width * double(grid.nx - 1) : 0;
      const std::size_t i0 = std::min(static_cast<std::size_t>(u), grid.nx - 1), i1 = std::min(i0 + 1, grid.nx - 1);
      const double a = u - double(i0);
      // Holes keep their true outline: the nearest node decides.
      if (!std::isfinite(z_at(a < 0.5 ? i0 : i1, jn))) continue;
      double acc = 0, wsum = 0;
      const std::size_t is[2] = {i0, i1}, js[2] = {j0, j1};
      const double wi[2] = {1 - a, a}, wj[2] = {1 - b, b};
      for (int q = 0; q < 2; ++q)
        for (int p = 0; p < 2; ++p) {
          const float z = z_at(is[p], js[q]);
          const double w = wi[p] * wj[q];
          if (!std::isfinite(z) || w <= 0) continue;
          acc += w * z;
          wsum += w;
        }
      if (wsum <= 0) continue;
      img.set(px, py, colormap_viridis(span > 0 ? (acc / wsum - o.z_min) / span : 0.5));
    }
  }
  return img;
}

}  // namespace cncstream::image
