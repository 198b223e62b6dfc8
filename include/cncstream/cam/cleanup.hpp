#pragma once
// Clean-up passes of a combined plan: the parts of a raster's rows where the
// material left by a previous tool exceeds a tolerance, so the second tool
// cuts only there.
#include <vector>

#include "cncstream/cam/cl_grid.hpp"
#include "cncstream/cam/raster.hpp"

namespace cncstream::cam {

// residual: per node of `grid`, material left (NaN off part). A row needs
// cleaning where some node within half a stepover across it holds more than
// `tol`; those stretches are grown by `reach` (the cutter radius) along the
// row and cut out of the row's polyline (cut points on a chord lie on or
// above the CL surface). Pieces keep the rows' order and directions.
std::vector<Polyline> cleanup_pieces(const RasterPath& path, const GridSpec& grid, const std::vector<double>& residual,
                                     double tol, double reach, bool passes_along_x);

}  // namespace cncstream::cam
