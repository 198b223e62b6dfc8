#pragma once
// The depth-buffer part of the CL engine: rows of a grid in cache-sized
// tiles; primitives are binned to the tiles their footprint touches, and each
// tile keeps the max of every primitive's drop height at its nodes.
#include <cstddef>
#include <vector>

#include "cl_contact.hpp"
#include "cncstream/cam/checkpoint.hpp"
#include "cl_primitives.hpp"
#include "cncstream/cam/cl_grid.hpp"
#include "cncstream/geometry/mesh.hpp"

namespace cncstream::cam::cl_detail {

// Rows [j0, j1) of `spec` into z (row-major, (j1 - j0) * spec.nx values).
// `faces`: face_offset of each of prims.faces, in its order.
// A node no primitive touches gets kNoContact. Tiles run as oneTBB tasks in
// the caller's task arena; `checkpoint` is called after each tile.
void rasterize_rows(const geometry::Mesh& mesh, const ClPrimitives& prims, const std::vector<FaceOffset>& faces,
                    const CutterShape& cutter, const GridSpec& spec,
                    std::size_t j0, std::size_t j1, double* z, const Checkpoint& checkpoint = {});

}  // namespace cncstream::cam::cl_detail
