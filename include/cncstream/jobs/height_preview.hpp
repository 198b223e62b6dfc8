#pragma once
// A job's tool-tip heights as a small height image for a preview, in work
// coordinates: an STL job's CL grid resampled, or a G-code program's cutting
// moves rasterised. The nodes span the cut's XY extent exactly (the first and
// last node lie on its edges), so a client can place the picture on the path.
#include <cstddef>
#include <vector>

#include "cncstream/cam/cl_grid.hpp"
#include "cncstream/cam/raster.hpp"
#include "cncstream/gcode/program.hpp"
#include "cncstream/geometry/vec3.hpp"
#include "cncstream/image/image.hpp"
#include "cncstream/image/map_grid.hpp"

namespace cncstream::jobs {

struct HeightPreview {
  image::MapGrid grid;                 // node (i, j) at (x0 + i*dx, y0 + j*dy), work coordinates
  std::vector<float> z;         // grid.size() tip heights; NaN: nothing cut near
  double z_min = 0, z_max = 0;  // the lowest and highest tip (the colour ramp's ends)

  bool empty() const { return z.empty(); }
  cam::XYBounds bounds() const;  // the nodes' extent
};

// Nodes a side at most: 1024 x 1024 floats is 4 MB, where the CL grid of a
// plaque (1.27 M nodes, doubles and flags) is 11 MB.
inline constexpr std::size_t kPreviewSideMax = 1024;

// The CL grid (model coordinates) resampled onto at most max_side nodes a
// side (never finer than the grid) over `extent` (model coordinates: the
// path's rows, which may reach a shorter last row the grid lacks), each node
// keeping the highest grid node under it (a thin ridge survives), then moved
// by `offset` into work coordinates. z_min/z_max are the whole grid's.
HeightPreview height_preview_from_grid(const cam::ClGrid& grid, const cam::XYBounds& extent, const geometry::Vec3& offset,
                                       std::size_t max_side = kPreviewSideMax);

// The cutting moves (not rapids) rasterised onto at most max_side nodes a
// side over their XY extent: a node keeps the lowest tip that passed over it
// (the deepest cut there; a plunge counts by its bottom). Nodes between rows
// are grown from their neighbours for up to 16 nodes; farther ones stay NaN.
// Empty when the program has no cutting move.
HeightPreview height_preview_from_trace(const gcode::ProgramTrace& trace, std::size_t max_side = 512);

// The picture (render_height_image): the long side max_px pixels, the other
// by the bounds' aspect, at least 1. Throws std::invalid_argument when empty.
image::RgbImage render_height_preview(const HeightPreview& h, int max_px, image::Rgb no_data);

}  // namespace cncstream::jobs
