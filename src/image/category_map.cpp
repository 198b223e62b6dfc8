// Categorical maps (one colour per category, e.g. the cutter chosen).
#include <algorithm>
#include <array>
#include <stdexcept>
#include <vector>

#include "cncstream/image/category_map.hpp"
#include "map_frame.hpp"

namespace cncstream::image {

namespace mf = map_frame;

namespace {
constexpr Rgb kNone{222, 222, 222};
}

Rgb category_colour(std::size_t k) {
  // Okabe & Ito (2008), black moved last: distinct for common colour-vision deficiencies.
  static constexpr std::array<Rgb, 8> kPalette = {{{230, 159, 0},
                                                   {86, 180, 233},
                                                   {0, 158, 115},
                                                   {240, 228, 66},
                                                   {0, 114, 178},
                                                   {213, 94, 0},
                                                   {204, 121, 167},
                                                   {60, 60, 60}}};
  return kPalette[k % kPalette.size()];
}

RgbImage render_category_map(const MapGrid& grid, std::span<const int> category,
                             const std::vector<MapCategory>& categories, const CategoryMapOptions& options) {
  if (grid.size() == 0) throw std::invalid_argument("category map: the grid is empty");
  if (category.size() != grid.size())
    throw std::invalid_argument("category map: " + std::to_string(category.size()) + " values for a grid of " +
                                std::to_string(grid.size()) + " nodes");
  std::vector<std::size_t> count(categories.size() + 1, 0);  // last: none
  for (std::size_t k = 0; k < category.size(); ++k) {
    const int c = category[k];
    if (c >= static_cast<int>(categories.size()))
      throw std::invalid_argument("category map: node " + std::to_string(k) + " has category " + std::to_string(c) +
                                  " but only " + std::to_string(categories.size()) + " are named");
    ++count[c < 0 ? categories.size() : static_cast<std::size_t>(c)];
  }
  auto share = [&](std::size_t n) { return mf::fixed(100.0 * n / category.size(), 1) + "%"; };
  std::vector<std::string> labels;
  for (std::size_t c = 0; c < categories.size(); ++c) labels.push_back(categories[c].name + "  " + share(count[c]));
  labels.push_back(options.none_label + "  " + share(count.back()));
  const int legend_w = 24 + std::max(mf::widest(labels), mf::widest({"Legend"}));
  const int legend_h = mf::kLineStep * static_cast<int>(labels.size() + 2);
  mf::Frame f = mf::make_frame(grid, options.max_map_pixels, options.title, options.subtitle, legend_w, legend_h);

  for (int py = 0; py < f.map_h; ++py)
    for (int px = 0; px < f.map_w; ++px) {
      const auto [i, j] = mf::node_at(f, grid, px, py);
      const int c = category[j * grid.nx + i];
      f.image.set(f.map_x + px, f.map_y + py, c < 0 ? kNone : categories[static_cast<std::size_t>(c)].colour);
    }
  int y = f.legend_y;
  f.image.draw_text(f.legend_x, y, "Legend", mf::kInk, mf::kTextScale);
  y += mf::kLineStep + 4;
  for (std::size_t c = 0; c < categories.size(); ++c, y += mf::kLineStep)
    mf::draw_swatch(f.image, f.legend_x, y, categories[c].colour, labels[c]);
  if (count.back() > 0) mf::draw_swatch(f.image, f.legend_x, y, kNone, labels.back());
  return std::move(f.image);
}

}  // namespace cncstream::image
