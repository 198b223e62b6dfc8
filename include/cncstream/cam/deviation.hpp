#pragma once
// Verification of a machined result against the design, independent of the
// CL engine: the design height at every stock node comes from vertical rays
// cast at the design mesh (top-most hit), and the deviation is machined -
// design (negative = gouge, positive = material left).
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "cncstream/cam/cl_grid.hpp"
#include "cncstream/cam/stock.hpp"
#include "cncstream/geometry/mesh.hpp"
#include "cncstream/image/deviation_map.hpp"

namespace cncstream::cam {

struct DesignHeights {
  GridSpec grid;
  std::vector<double> z;                // top-most hit; NaN where off part
  std::vector<std::uint8_t> off_part;   // 1 where the vertical ray misses the mesh
  std::size_t on_part = 0;
};

// Casts a vertical ray through every node of `grid` (hits on a triangle's
// edge or corner count). Triangles seen edge-on from above are skipped: the
// faces around them give the same top-most heights.
DesignHeights design_heights(const geometry::Mesh& design, const GridSpec& grid);

struct DeviationAt {
  double value = 0;  // machined - design, mm
  double x = 0, y = 0;
  std::size_t i = 0, j = 0;
};

struct DeviationStats {
  double tolerance = 0;
  std::size_t on_part = 0, off_part = 0;
  std::size_t gouged = 0;  // nodes below design by more than the tolerance
  std::size_t excess = 0;  // nodes above design by more than the tolerance
  bool has_gouge = false;  // any node below the design at all
  DeviationAt largest_gouge;   // most negative deviation (valid if has_gouge)
  DeviationAt largest_excess;  // most positive deviation
  double mean_excess = 0;      // mean over on-part nodes of max(0, deviation)
  double mean_deviation = 0;   // mean over on-part nodes
  // Scallop statistics: the distribution over on-part nodes of the material
  // left, max(0, deviation): median, 90th and 99th percentiles, and RMS.
  double excess_p50 = 0, excess_p90 = 0, excess_p99 = 0, excess_rms = 0;

  std::string summary() const;  // a few lines for a person
};

struct DeviationResult {
  GridSpec grid;
  std::vector<double> deviation;       // NaN where off part
  std::vector<std::uint8_t> off_part;
  DeviationStats stats;
};

// Throws std::invalid_argument if the grids differ or tolerance <= 0.
DeviationResult compare_to_design(const HeightFieldStock& machined, const DesignHeights& design, double tolerance);

// The deviation map (see image/deviation_map.hpp) of a result.
image::RgbImage render_deviation(const DeviationResult& result, const std::string& title, const std::string& subtitle = {},
                          int max_map_pixels = 800);
void write_deviation_png(const std::filesystem::path& path, const DeviationResult& result, const std::string& title,
                         const std::string& subtitle = {});

}  // namespace cncstream::cam
