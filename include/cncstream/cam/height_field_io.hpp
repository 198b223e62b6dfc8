#pragma once
// Height-field files: raw little-endian float32 values (row-major, x fastest,
// first row at y0) in `<name>.f32`, and a text sidecar `<name>.f32.txt`
// giving the grid:
//     cncstream height field 1
//     nx 1201
//     ny 1001
//     x0 0
//     y0 0
//     dx 0.1
//     dy 0.1
//     nodata nan
// NaN marks nodes without a value. Shared by the stock export and the CL
// grid export. A machined surface in work coordinates may also say where
// the part's model sat (work = model + offset), so a viewer or a verify can
// place the design on it:
//     work_offset_x 0
//     work_offset_y 0
//     work_offset_z -10.5
// and where that work zero sat on the machine (machine coordinates of work
// zero, G5x + G92, when the surface was saved), so a later setup with its own
// work zero elsewhere places the surface where it physically is:
//     work_origin_x 120
//     work_origin_y 80
//     work_origin_z -42
#include <filesystem>
#include <fstream>
#include <optional>
#include <span>
#include <stdexcept>
#include <vector>

#include "cncstream/cam/cl_grid.hpp"
#include "cncstream/geometry/vec3.hpp"

namespace cncstream::cam {

struct HeightFieldData {
  GridSpec grid;
  std::vector<float> z;  // grid.size() values, NaN = no value
  std::optional<geometry::Vec3> work_offset;  // work = model + offset, where the file says
  std::optional<geometry::Vec3> work_origin;  // machine coordinates of the work zero the surface is relative to
};

class HeightFieldError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The sidecar's path for a given data path: "<path>.txt".
std::filesystem::path height_field_sidecar(const std::filesystem::path& data_path);

// Writes a grid in row order, a block of values at a time (a grid larger
// than memory can be streamed); finish() checks the count and writes the
// sidecar.
class HeightFieldWriter {
 public:
  HeightFieldWriter(const std::filesystem::path& data_path, const GridSpec& grid,
                    std::optional<geometry::Vec3> work_offset = std::nullopt, std::optional<geometry::Vec3> work_origin = std::nullopt);
  void append(std::span<const double> z);
  void finish();

 private:
  std::filesystem::path path_;
  GridSpec grid_;
  std::optional<geometry::Vec3> work_offset_, work_origin_;
  std::ofstream out_;
  std::size_t written_ = 0;
};

// Writes both files. Throws HeightFieldError naming the path on failure and
// std::invalid_argument if z.size() != grid.size().
void write_height_field(const std::filesystem::path& data_path, const GridSpec& grid, std::span<const double> z,
                        std::optional<geometry::Vec3> work_offset = std::nullopt, std::optional<geometry::Vec3> work_origin = std::nullopt);

// Reads both files; errors name the file and the sidecar line, or the data
// file's expected and actual size.
HeightFieldData read_height_field(const std::filesystem::path& data_path);

}  // namespace cncstream::cam
