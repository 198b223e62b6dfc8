#pragma once
// Shared page layout of the map pictures (private to src/image): title,
// map area with north up, scale bar and north arrow under the map, and a
// legend panel on the right whose content each renderer draws.
#include <cstddef>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "cncstream/image/image.hpp"
#include "cncstream/image/map_grid.hpp"

namespace cncstream::image::map_frame {

inline constexpr Rgb kInk{25, 25, 25};
inline constexpr Rgb kFaint{110, 110, 110};
inline constexpr Rgb kPaper{255, 255, 255};
inline constexpr int kTextScale = 2;  // legend and label text
inline constexpr int kTitleScale = 3;
inline constexpr int kLineStep = 22;  // one legend text line at kTextScale

struct Frame {
  RgbImage image;
  int map_x = 0, map_y = 0, map_w = 0, map_h = 0;
  double px_per_mm = 1;
  int legend_x = 0, legend_y = 0, legend_w = 0;
};

// Lays out the page, draws title, subtitle, map border, scale bar and north
// arrow; legend_w x legend_h is reserved for the caller's legend.
Frame make_frame(const MapGrid& grid, int max_map_pixels, const std::string& title, const std::string& subtitle,
                 int legend_w, int legend_h);

// The node under the centre of map pixel (px, py), north up.
std::pair<std::size_t, std::size_t> node_at(const Frame& f, const MapGrid& grid, int px, int py);
// Node index range [i0, i1] x [j0, j1] that map pixel (px, py) covers.
struct NodeRange {
  std::size_t i0, i1, j0, j1;
};
NodeRange nodes_under(const Frame& f, const MapGrid& grid, int px, int py);
// Continuous node coordinates of a pixel centre (node (i, j) at (i, j)).
std::pair<double, double> node_coords(const Frame& f, const MapGrid& grid, int px, int py);

// Vertical colour bar at (x, y), w x h; colour_of(t) for t in [0, 1] from the
// bottom to the top; labels at their t, right of the bar, with tick marks.
void draw_colour_bar(RgbImage& img, int x, int y, int w, int h, const std::function<Rgb(double)>& colour_of,
                     const std::vector<std::pair<double, std::string>>& labels);
// A filled swatch with an outline and a text label to its right.
void draw_swatch(RgbImage& img, int x, int y, Rgb colour, const std::string& label);

// Width in pixels of the widest line at kTextScale.
int widest(const std::vector<std::string>& lines);
// "12.345" with as many decimals as `decimals`.
std::string fixed(double v, int decimals);
// Decimals that tell apart values across `range` (mm).
int decimals_for(double range);

}  // namespace cncstream::image::map_frame
