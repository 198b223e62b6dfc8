#pragma once
// Which primitives of a mesh the CL engine draws. Every non-vertical facet
// draws its interior contact; every unique edge and vertex is drawn once,
// except those provably unable to raise the envelope (see cl_primitives.cpp).
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "cl_contact.hpp"
#include "cncstream/geometry/mesh.hpp"

namespace cncstream::cl_detail {

struct ClPrimitives {
  std::vector<std::uint32_t> faces;                    // facets with an interior contact
  std::vector<std::array<std::uint32_t, 2>> edges;     // drawn edges, highest end first
  std::vector<std::uint32_t> vertices;                 // drawn vertices, highest first
  std::size_t edges_total = 0;                         // unique edges in the mesh
  std::size_t vertices_total = 0;                      // vertices used by some facet
};

// skip_concave: leave out manifold edges whose two facets meet in a valley or
// are coplanar (and vertices left with no drawn edge are drawn instead).
ClPrimitives select_primitives(const Mesh& mesh, const CutterShape& cutter, bool skip_concave);

}  // namespace cncstream::cl_detail
