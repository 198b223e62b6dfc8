#pragma once
// Map of signed deviations (machined - design, mm): gouges (below design by
// more than the tolerance) in reds, excess material (above by more than the
// tolerance) in blues, within tolerance in pale green, off-part in grey. The
// legend names each colour with its values and gives the extremes.
#include <cstdint>
#include <span>
#include <string>
#include <utility>

#include "cncstream/image/image.hpp"
#include "cncstream/image/map_grid.hpp"

namespace cncstream::image {

struct DeviationMapOptions {
  std::string title;
  std::string subtitle;
  double tolerance = 0.05;  // mm, > 0
  int max_map_pixels = 800;
};

// The colours, so tests and callers can tell what a pixel means.
struct DeviationPalette {
  static constexpr Rgb within{196, 232, 196};
  static constexpr Rgb off_part{222, 222, 222};
  // Light at the tolerance, dark at the largest deviation of that sign.
  static Rgb gouge(double severity);   // severity in [0, 1]
  static Rgb excess(double severity);  // severity in [0, 1]
};

// The map's colour for one deviation v (mm): within +/-tolerance the pale
// green, beyond it a gouge or excess colour whose severity runs from the
// tolerance to the worst value of that sign (largest_gouge, largest_excess:
// the magnitudes, >= 0). The map and the 3-D viewer colour with this.
struct DeviationScale {
  double tolerance = 0.05;
  double largest_gouge = 0, largest_excess = 0;
  Rgb colour(double v) const;
};

// The map's legend (the colours, a colour bar over the data's range, the
// extremes and counts), also drawn beside the 3-D viewer's screenshots.
struct DeviationLegend {
  double tolerance = 0.05;
  double lo = 0, hi = 0;         // most negative (<= 0) and most positive (>= 0) deviation, mm
  std::string lo_at, hi_at;      // where they are ("at x 12.00 y 3.40"), or empty
  std::size_t gouged = 0, excess = 0, on_part = 0;
};
// Width and height in pixels.
std::pair<int, int> deviation_legend_size(const DeviationLegend& legend);
void draw_deviation_legend(RgbImage& image, int x, int y, const DeviationLegend& legend);

// deviation: grid.size() values; off_part: empty or grid.size() flags (1 = no
// design surface there). Where a pixel covers several nodes it shows the
// worst one (a gouge first), so a one-node gouge never disappears.
RgbImage render_deviation_map(const MapGrid& grid, std::span<const double> deviation,
                              std::span<const std::uint8_t> off_part, const DeviationMapOptions& options);

}  // namespace cncstream::image
