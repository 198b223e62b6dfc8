#pragma once
// Shaded-relief picture of a height field: hill shading from a light
// direction multiplied into a viridis colour ramp by height, north (+y) up,
// with a title, a colour bar labelled in mm, a scale bar and a north arrow.
#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "cncstream/image/image.hpp"
#include "cncstream/image/map_grid.hpp"

namespace cncstream::image {

struct HeightMapOptions {
  std::string title;
  std::string subtitle;                // optional second line (cutter, grid step...)
  double light_azimuth_deg = 315;      // where the light comes from, clockwise from north
  double light_elevation_deg = 45;     // above the horizon
  double vertical_exaggeration = 1;    // steepens the shading only, not the colours
  int max_map_pixels = 800;            // the map's longer side
  std::optional<double> z_min, z_max;  // colour range; default: the data's range
};

// values: grid.size() heights (mm). invalid: empty, or grid.size() flags with
// 1 = no value there (drawn in a neutral grey). Throws std::invalid_argument
// on mismatched sizes or an empty grid.
RgbImage render_height_map(const MapGrid& grid, std::span<const double> values,
                           std::span<const std::uint8_t> invalid, const HeightMapOptions& options);

// The map alone, for a client to draw under its own overlay: no frame,
// legend or shading, so a pixel's colour is the viridis colour of its height
// between z_min and z_max (a reader can tell the height back from it).
struct HeightImageOptions {
  int width = 0, height = 0;          // pixels, 1..8000 each
  double z_min = 0, z_max = 0;        // the ramp's ends
  Rgb no_data{205, 205, 205};
};

// values: grid.size() heights, NaN where there is none. The image spans the
// nodes' centres exactly: pixel edges 0 and width lie on the first and last
// column of nodes (x0 and x0 + (nx-1)dx), north (+y) up. Heights are blended
// bilinearly between valid nodes; a pixel whose nearest node has no value is
// no_data. Throws std::invalid_argument on a bad size or mismatched values.
RgbImage render_height_image(const MapGrid& grid, std::span<const float> values, const HeightImageOptions& options);

}  // namespace cncstream::image
