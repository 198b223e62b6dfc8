#include "cl_primitives.hpp"

#include <algorithm>
#include <numeric>

namespace cncstream::cl_detail {

namespace {

struct FacetSlot {
  std::uint32_t facet[2] = {UINT32_MAX, UINT32_MAX};
  std::uint32_t opposite[2] = {UINT32_MAX, UINT32_MAX};
  std::uint32_t count = 0;
};

// A manifold edge between facets A and B can be left out when the surface
// there is a valley or flat seen from above: A's far vertex and B's far vertex
// lie on opposite sides of the edge in XY, and each lies on or above the
// other's plane. Why that is exact: if the drop height over the whole mesh
// were attained at a point q of this edge, then q is the maximum of the
// concave function p.z - h(|p - c|) over A; unless q is also the tangent
// point of A's plane (which A's own interior contact then reports, hence the
// inclusive test in face_offset), the function increases from q across the
// edge, and B, lying on or above A's plane on that side, would give a higher
// value near q -- a contradiction. Steep facets are excluded because their
// interior contact is reported without tolerance; mixed horizontal /
// non-horizontal pairs because their contact points are shifted differently.
bool edge_is_redundant(const Mesh& mesh, const CutterShape& cutter, std::uint32_t a, std::uint32_t b,
                       const FacetSlot& slot) {
  if (slot.count != 2 || slot.facet[0] == slot.facet[1]) return false;
  const Vec3 pa = mesh.vertices[a], pb = mesh.vertices[b];
  const Vec3 oa = mesh.vertices[slot.opposite[0]], ob = mesh.vertices[slot.opposite[1]];
  const Vec3 na = upward_normal(pa, pb, oa), nb = upward_normal(pa, pb, ob);
  if (na.z < kSteepNz || nb.z < kSteepNz) return false;
  auto facet_offset = [&](std::uint32_t t) {
    const auto& tri = mesh.triangles[t];
    return face_offset(mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]], cutter);
  };
  const FaceOffset fa = facet_offset(slot.facet[0]), fb = facet_offset(slot.facet[1]);
  if (!fa.active || !fb.active || fa.horizontal != fb.horizontal) return false;
  const double ex = pb.x - pa.x, ey = pb.y - pa.y;
  const double side_a = ex * (oa.y - pa.y) - ey * (oa.x - pa.x);
  const double side_b = ex * (ob.y - pa.y) - ey * (ob.x - pa.x);
  if (!(side_a * side_b < 0)) return false;
  return dot(ob - pa, na) >= 0 && dot(oa - pa, nb) >= 0;
}

}  // namespace

ClPrimitives select_primitives(const Mesh& mesh, const CutterShape& cutter, bool skip_concave) {
  ClPrimitives out;
  const std::size_t nv = mesh.vertices.size();
  std::vector<std::uint8_t> used(nv, 0);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    for (auto idx : tri) used[idx] = 1;
    const FaceOffset f = face_offset(mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]], cutter);
    if (f.active) out.faces.push_back(static_cast<std::uint32_t>(t));
  }
  out.vertices_total = static_cast<std::size_t>(std::count(used.begin(), used.end(), 1));

  std::vector<MeshEdge> all = unique_edges(mesh);  // sorted by (a, b)
  out.edges_total = all.size();
  std::vector<std::uint8_t> drawn(all.size(), 1);
  if (skip_concave && !all.empty()) {
    // Edge lookup by lower vertex: edges are sorted by (a, b).
    std::vector<std::uint32_t> first(nv + 1, 0);
    for (const auto& e : all) ++first[e.a + 1];
    std::partial_sum(first.begin(), first.end(), first.begin());
    std::vector<FacetSlot> slots(all.size());
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const auto& tri = mesh.triangles[t];
      for (int k = 0; k < 3; ++k) {
        std::uint32_t a = tri[k], b = tri[(k + 1) % 3];
        if (a == b) continue;
        if (a > b) std::swap(a, b);
        for (std::uint32_t e = first[a]; e < first[a + 1]; ++e) {
          if (all[e].b != b) continue;
          FacetSlot& s = slots[e];
          if (s.count < 2) {
            s.facet[s.count] = static_cast<std::uint32_t>(t);
            s.opposite[s.count] = tri[(k + 2) % 3];
          }
          ++s.count;
          break;
        }
      }
    }
    for (std::size_t e = 0; e < all.size(); ++e)
      if (all[e].uses == 2 && edge_is_redundant(mesh, cutter, all[e].a, all[e].b, slots[e])) drawn[e] = 0;
  }

  std::vector<std::uint8_t> covered(nv, 0);
  for (std::size_t e = 0; e < all.size(); ++e) {
    if (!drawn[e]) continue;
    out.edges.push_back({all[e].a, all[e].b});
    covered[all[e].a] = covered[all[e].b] = 1;
  }
  all.clear();
  all.shrink_to_fit();
  // A drawn edge includes its end points, so only vertices with no drawn
  // edge (all neighbours skipped, or only degenerate facets) are drawn.
  for (std::size_t v = 0; v < nv; ++v)
    if (used[v] && !covered[v]) out.vertices.push_back(static_cast<std::uint32_t>(v));

  // Highest first: the rasterizer and the point query then meet the
  // primitives most likely to set the envelope early and cull the rest.
  const auto& V = mesh.vertices;
  std::sort(out.edges.begin(), out.edges.end(), [&](const auto& p, const auto& q) {
    const double zp = std::fmax(V[p[0]].z, V[p[1]].z), zq = std::fmax(V[q[0]].z, V[q[1]].z);
    return zp != zq ? zp > zq : p < q;
  });
  std::sort(out.vertices.begin(), out.vertices.end(), [&](std::uint32_t p, std::uint32_t q) {
    return V[p].z != V[q].z ? V[p].z > V[q].z : p < q;
  });
  return out;
}

}  // namespace cncstream::cl_detail
