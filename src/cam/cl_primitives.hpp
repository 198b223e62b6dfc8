#pragma once
// Which primitives of a mesh the CL engine draws. Every non-vertical facet
// draws its interior contact; every unique edge and vertex is drawn once,
// except those provably unable to raise the envelope (see cl_primitives.cpp).
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "cl_contact.hpp"
#include "cncstream/geometry/mesh.hpp"

namespace cncstream::cam::cl_detail {

// Where a drawn edge can set the envelope with a contact inside the edge: the
// signed XY distance d of the node from the edge's line (d = (node - a) .
// (uy, -ux)) must lie in [lo, hi]. Outside, an interior contact's normal is
// outside the cone of the two facets' normals, so one facet would pierce the
// cutter there: the facets' own contacts report a higher value. Only the
// contacts at the edge's end points remain (vertex drops).
struct EdgeBand {
  double lo = -HUGE_VAL, hi = HUGE_VAL;
  bool trimmed() const { return lo > -HUGE_VAL || hi < HUGE_VAL; }
};

// The band of a convex manifold edge a-b between facets with upward unit
// normals na and nb (both non-steep), for this cutter.
EdgeBand edge_band(const geometry::Vec3& a, const geometry::Vec3& b, const geometry::Vec3& na, const geometry::Vec3& nb, const CutterShape& cutter);

struct ClPrimitives {
  std::vector<std::uint32_t> faces;                    // facets with an interior contact
  std::vector<std::array<std::uint32_t, 2>> edges;     // drawn edges, highest end first
  std::vector<EdgeBand> edge_bands;                    // per drawn edge
  std::vector<std::uint32_t> vertices;                 // drawn vertices, highest first
  std::size_t edges_total = 0;                         // unique edges in the mesh
  std::size_t vertices_total = 0;                      // vertices used by some facet
};

// skip_concave: leave out manifold edges whose two facets meet in a valley or
// are coplanar (and vertices left with no drawn edge are drawn instead).
ClPrimitives select_primitives(const geometry::Mesh& mesh, const CutterShape& cutter, bool skip_concave);

}  // namespace cncstream::cam::cl_detail
