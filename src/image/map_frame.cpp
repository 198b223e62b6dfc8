// Page layout shared by the map renderers.
#include "map_frame.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cncstream::image::map_frame {

namespace {

constexpr int kMargin = 16;
constexpr int kGap = 24;
constexpr int kUnderMap = 56;  // scale bar and north arrow row

// 1, 2 or 5 times a power of ten, at most `limit`.
double nice_length(double limit) {
  const double p = std::pow(10.0, std::floor(std::log10(limit)));
  for (double m : {5.0, 2.0, 1.0})
    if (m * p <= limit) return m * p;
  return p;
}

void draw_scale_bar(Frame& f) {
  RgbImage& img = f.image;
  const double mm = nice_length(f.map_w * 0.3 / f.px_per_mm);
  const int len = std::max(1, static_cast<int>(std::lround(mm * f.px_per_mm)));
  const int x = f.map_x, y = f.map_y + f.map_h + 14;
  // Half black, half white so the ends read clearly on any background.
  img.fill_rect(x, y, len, 8, kInk);
  img.fill_rect(x + len / 2, y + 1, len - len / 2 - 1, 6, kPaper);
  const std::string label = (mm >= 1 ? fixed(mm, 0) : fixed(mm, decimals_for(mm))) + " mm";
  img.draw_text(x, y + 14, label, kInk, kTextScale);
}

void draw_north_arrow(Frame& f) {
  RgbImage& img = f.image;
  const int cx = f.map_x + f.map_w - 14, top = f.map_y + f.map_h + 8;
  // A solid triangle pointing up, then the letter N beside it.
  for (int r = 0; r < 14; ++r) img.fill_rect(cx - r / 2, top + r, r + 1, 1, kInk);
  img.fill_rect(cx - 1, top + 14, 3, 18, kInk);
  img.draw_text(cx - 18 - RgbImage::text_width("N", kTextScale), top + 8, "N", kInk, kTextScale);
}

}  // namespace

std::string fixed(double v, int decimals) {
  std::string s = fmt::format("{:.{}f}", v, std::clamp(decimals, 0, 6));
  if (s == "-0" || s.find_first_not_of("-0.") == std::string::npos) s = s.substr(s[0] == '-' ? 1 : 0);
  return s;
}

int decimals_for(double range) {
  if (!(range > 0) || !std::isfinite(range)) return 3;
  return std::clamp(static_cast<int>(std::ceil(-std::log10(range))) + 2, 0, 4);
}

int widest(const std::vector<std::string>& lines) {
  int w = 0;
  for (const auto& s : lines) w = std::max(w, RgbImage::text_width(s, kTextScale));
  return w;
}

Frame make_frame(const MapGrid& grid, int max_map_pixels, const std::string& title, const std::string& subtitle,
                 int legend_w, int legend_h) {
  if (grid.nx == 0 || grid.ny == 0) throw std::invalid_argument("map grid is empty");
  if (!(grid.dx > 0) || !(grid.dy > 0)) throw std::invalid_argument("map grid step must be positive");
  if (max_map_pixels < 16 || max_map_pixels > 8000)
    throw std::invalid_argument("map size " + std::to_string(max_map_pixels) + " px is outside 16..8000");
  Frame f;
  const double ex = static_cast<double>(grid.nx) * grid.dx, ey = static_cast<double>(grid.ny) * grid.dy;
  f.px_per_mm = max_map_pixels / std::max(ex, ey);
  f.map_w = std::max(1, static_cast<int>(std::lround(ex * f.px_per_mm)));
  f.map_h = std::max(1, static_cast<int>(std::lround(ey * f.px_per_mm)));
  // The scale-bar row needs room for its label and the north arrow.
  f.map_w = std::max(f.map_w, 1);
  int top = kMargin;
  const int title_h = title.empty() ? 0 : RgbImage::text_height(kTitleScale) + 8;
  const int sub_h = subtitle.empty() ? 0 : RgbImage::text_height(kTextScale) + 8;
  top += title_h + sub_h + (title_h + sub_h > 0 ? 6 : 0);
  f.map_x = kMargin;
  f.map_y = top;
  f.legend_x = f.map_x + std::max(f.map_w, 160) + kGap;
  f.legend_y = top;
  f.legend_w = legend_w;
  const int width = std::max({f.legend_x + legend_w + kMargin,
                              kMargin + RgbImage::text_width(title, kTitleScale) + kMargin,
                              kMargin + RgbImage::text_width(subtitle, kTextScale) + kMargin});
  const int height = std::max(top + f.map_h + kUnderMap, top + legend_h) + kMargin;
  f.image = RgbImage(width, height, kPaper);
  if (!title.empty()) f.image.draw_text(kMargin, kMargin, title, kInk, kTitleScale);
  if (!subtitle.empty()) f.image.draw_text(kMargin, kMargin + title_h, subtitle, kFaint, kTextScale);
  f.image.draw_rect(f.map_x - 1, f.map_y - 1, f.map_w + 2, f.map_h + 2, kInk);
  draw_scale_bar(f);
  draw_north_arrow(f);
  return f;
}

std::pair<double, double> node_coords(const Frame& f, const MapGrid& grid, int px, int py) {
  // Node (i, j) owns the cell [i*dx, (i+1)*dx) from the map's west edge.
  const double xm = (px + 0.5) / f.px_per_mm, ym = (f.map_h - py - 0.5) / f.px_per_mm;
  return {xm / grid.dx - 0.5, ym / grid.dy - 0.5};
}

std::pair<std::size_t, std::size_t> node_at(const Frame& f, const MapGrid& grid, int px, int py) {
  const auto [u, v] = node_coords(f, grid, px, py);
  const auto clampi = [](double t, std::size_t n) {
    return static_cast<std::size_t>(std::clamp(std::lround(t), 0L, static_cast<long>(n) - 1));
  };
  return {clampi(u, grid.nx), clampi(v, grid.ny)};
}

NodeRange nodes_under(const Frame& f, const MapGrid& grid, int px, int py) {
  const double x0 = px / f.px_per_mm / grid.dx, x1 = (px + 1) / f.px_per_mm / grid.dx;
  const double y0 = (f.map_h - py - 1) / f.px_per_mm / grid.dy, y1 = (f.map_h - py) / f.px_per_mm / grid.dy;
  const auto lo = [](double t, std::size_t n) {
    return static_cast<std::size_t>(std::clamp(static_cast<long>(std::floor(t)), 0L, static_cast<long>(n) - 1));
  };
  const auto hi = [](double t, std::size_t n) {
    return static_cast<std::size_t>(std::clamp(static_cast<long>(std::ceil(t)) - 1, 0L, static_cast<long>(n) - 1));
  };
  NodeRange r{lo(x0, grid.nx), hi(x1, grid.nx), lo(y0, grid.ny), hi(y1, grid.ny)};
  r.i1 = std::max(r.i1, r.i0);
  r.j1 = std::max(r.j1, r.j0);
  return r;
}

void draw_colour_bar(RgbImage& img, int x, int y, int w, int h, const std::function<Rgb(double)>& colour_of,
                     const std::vector<std::pair<double, std::string>>& labels) {
  for (int r = 0; r < h; ++r) {
    const double t = h > 1 ? 1.0 - static_cast<double>(r) / (h - 1) : 0.5;
    img.fill_rect(x, y + r, w, 1, colour_of(t));
  }
  img.draw_rect(x - 1, y - 1, w + 2, h + 2, kInk);
  const int th = RgbImage::text_height(kTextScale);
  // Ticks sit at their values; labels whose values are close (a narrow band
  // of a wide range) are spread apart so no two overlap, in value order.
  struct Placed {
    int tick, text;
    const std::string* label;
  };
  std::vector<Placed> placed;
  for (const auto& [t, text] : labels) {
    const int ty = y + static_cast<int>(std::lround((1.0 - std::clamp(t, 0.0, 1.0)) * (h - 1)));
    // The label's middle (ignoring the descender rows) on the tick.
    placed.push_back({ty, ty - (th * 7 / 9) / 2, &text});
  }
  std::stable_sort(placed.begin(), placed.end(), [](const Placed& a, const Placed& b) { return a.tick < b.tick; });
  const int gap = th + 1;
  for (std::size_t k = 1; k < placed.size(); ++k)
    placed[k].text = std::max(placed[k].text, placed[k - 1].text + gap);
  // Pushed past the bar's bottom: shift the stack back up.
  const int bottom = y + h - (th * 7 / 9) / 2;
  for (std::size_t k = placed.size(); k-- > 0;) {
    const int limit = k + 1 < placed.size() ? placed[k + 1].text - gap : bottom;
    placed[k].text = std::min(placed[k].text, limit);
  }
  for (const auto& p : placed) {
    img.fill_rect(x + w, p.tick, 6, 1, kInk);
    img.draw_text(x + w + 10, p.text, *p.label, kInk, kTextScale);
  }
}

void draw_swatch(RgbImage& img, int x, int y, Rgb colour, const std::string& label) {
  img.fill_rect(x, y, 16, 16, colour);
  img.draw_rect(x, y, 16, 16, kInk);
  img.draw_text(x + 24, y + 1, label, kInk, kTextScale);
}

}  // namespace cncstream::image::map_frame
