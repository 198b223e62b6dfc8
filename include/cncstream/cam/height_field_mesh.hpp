#pragma once
// A height field as a closed solid: the top surface (two triangles per grid
// cell), four side walls down to a flat bottom, and the bottom as a fan.
// Every edge is shared by exactly two triangles; normals face outward.
#include <filesystem>
#include <span>

#include "cncstream/cam/cl_grid.hpp"
#include "cncstream/geometry/mesh.hpp"

namespace cncstream::cam {

// Throws std::invalid_argument for a grid smaller than 2 x 2, a size
// mismatch, a non-finite height or a bottom not below every height.
geometry::Mesh height_field_solid(const GridSpec& grid, std::span<const double> z, double bottom);

// height_field_solid written with write_stl_binary.
void write_height_field_stl(const std::filesystem::path& path, const GridSpec& grid, std::span<const double> z,
                            double bottom);

}  // namespace cncstream::cam
