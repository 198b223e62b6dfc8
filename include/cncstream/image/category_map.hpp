#pragma once
// Map of a category per node (e.g. which cutter machines each spot), with a
// legend of colour swatches, names and the share of nodes in each.
#include <span>
#include <string>
#include <vector>

#include "cncstream/image/image.hpp"
#include "cncstream/image/map_grid.hpp"

namespace cncstream::image {

struct MapCategory {
  std::string name;
  Rgb colour;
};

// A colour-blind-safe qualitative palette (Okabe-Ito), cycling past 8.
Rgb category_colour(std::size_t k);

struct CategoryMapOptions {
  std::string title;
  std::string subtitle;
  std::string none_label = "none";  // legend text for nodes with category < 0
  int max_map_pixels = 800;
};

// category: grid.size() indices into `categories`, or -1 for none (grey).
// Throws std::invalid_argument for an index past the list.
RgbImage render_category_map(const MapGrid& grid, std::span<const int> category,
                             const std::vector<MapCategory>& categories, const CategoryMapOptions& options);

}  // namespace cncstream::image
