#pragma once
// The stock a job starts from, as the operator gives it (`--stock`):
//   auto            the part's box grown by 1 mm on the sides and the top
//   auto:M          ... grown by M mm
//   X0,Y0,Z0:X1,Y1,Z1   a block, in work coordinates (where G54 is set)
//   FILE.f32        a height map a simulated cut left (`cncsim --result`,
//                   work coordinates), so a job can go on from an earlier one
#include <filesystem>
#include <optional>
#include <string_view>

#include "cncstream/cam/height_field_io.hpp"
#include "cncstream/geometry/vec3.hpp"

namespace cncstream::jobs {

struct StockSpec {
  enum class Kind { Auto, Box, HeightMap };
  Kind kind = Kind::Auto;
  double margin = 1.0;  // Auto
  geometry::Box3 box;             // Box: work coordinates
  std::filesystem::path height_map;
  // This job's work zero in machine coordinates (G5x + G92, as $# reports
  // them; `--work-origin`), to place a height map that records the work zero
  // it was saved with: the surface moves by (its origin − this one), so a
  // second setup with its zero elsewhere sees the stock where it physically
  // is. Unknown with a map that records one: refused.
  std::optional<geometry::Vec3> work_origin;
};

// Throws std::invalid_argument naming the text and what is wrong with it.
StockSpec parse_stock_spec(std::string_view text);

// The stock in work coordinates: its box (for a height map, the map's
// extent and its highest value above the lowest of the part), and the map
// itself when there is one. `part` is the part's box in work coordinates.
struct WorkStock {
  geometry::Box3 box;
  std::optional<cam::HeightFieldData> heights;
  // Height of the stock's top at (x, y), work coordinates: the box's top, or
  // the map's value at the nearest node (the box's top off the map or where
  // it holds no value).
  double top_at(double x, double y) const;
};

// Reads the height map where there is one, placed by the recorded work
// origins (a map without one is read in this job's work coordinates, as
// before origins were recorded). Throws std::invalid_argument when the stock
// does not contain the part's footprint or is below its top, or when the map
// records a work origin and this job's is unknown (naming the map's).
WorkStock resolve_stock(const StockSpec& spec, const geometry::Box3& part);

}  // namespace cncstream::jobs
