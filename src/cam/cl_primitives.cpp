#include "cl_primitives.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace cncstream::cam::cl_detail {

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
bool edge_is_redundant(const geometry::Mesh& mesh, const CutterShape& cutter, std::uint32_t a, std::uint32_t b,
                       const FacetSlot& slot) {
  if (slot.count != 2 || slot.facet[0] == slot.facet[1]) return false;
  const geometry::Vec3 pa = mesh.vertices[a], pb = mesh.vertices[b];
  const geometry::Vec3 oa = mesh.vertices[slot.opposite[0]], ob = mesh.vertices[slot.opposite[1]];
  const geometry::Vec3 na = upward_normal(pa, pb, oa), nb = upward_normal(pa, pb, ob);
  if (na.z < kSteepNz || nb.z < kSteepNz) return false;
  auto facet_offset = [&](std::uint32_t t) {
    const auto& tri = mesh.triangles[t];
    return face_offset(mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]], cutter);
  };
  const FaceOffset fa = facet_offset(slot.facet[0]), fb = facet_offset(slot.facet[1]);
  if (!fa.active || !fb.active || fa.horizontal != fb.horizontal) return false;
  // A facet at a straight band's slope touches along a segment, of which its
  // face offset reports one point: the argument above needs the one.
  if (fa.ambiguous || fb.ambiguous) return false;
  const double ex = pb.x - pa.x, ey = pb.y - pa.y;
  const double side_a = ex * (oa.y - pa.y) - ey * (oa.x - pa.x);
  const double side_b = ex * (ob.y - pa.y) - ey * (ob.x - pa.x);
  if (!(side_a * side_b < 0)) return false;
  return dot(ob - pa, na) >= 0 && dot(oa - pa, nb) >= 0;
}

// A convex (ridge) edge: each facet's far vertex lies below the other's plane.
bool edge_is_convex(const geometry::Mesh& mesh, std::uint32_t a, std::uint32_t b, const FacetSlot& slot, geometry::Vec3& na, geometry::Vec3& nb) {
  if (slot.count != 2 || slot.facet[0] == slot.facet[1]) return false;
  const geometry::Vec3 pa = mesh.vertices[a], pb = mesh.vertices[b];
  const geometry::Vec3 oa = mesh.vertices[slot.opposite[0]], ob = mesh.vertices[slot.opposite[1]];
  na = upward_normal(pa, pb, oa);
  nb = upward_normal(pa, pb, ob);
  if (na.z < kSteepNz || nb.z < kSteepNz) return false;
  return dot(ob - pa, na) < 0 && dot(oa - pa, nb) < 0;
}

}  // namespace

EdgeBand edge_band(const geometry::Vec3& a, const geometry::Vec3& b, const geometry::Vec3& na, const geometry::Vec3& nb, const CutterShape& c) {
  const double dx = b.x - a.x, dy = b.y - a.y, dz = b.z - a.z;
  const double L = std::sqrt(dx * dx + dy * dy), len = std::sqrt(L * L + dz * dz);
  if (!(L > 1e-12 * (1 + len))) return {};  // (near) vertical edge: no band
  if (c.general) return {};                  // (not derived for band profiles: drawn in full)
  const double ux = dx / L, uy = dy / L;
  const double sin_b = dz / len, cos_b = L / len;
  // In the plane normal to the edge: w horizontal (the direction of d), bv
  // the upward direction. A contact normal at angle phi from bv has
  // w-component sin(phi), and the node lies at d = g(sin phi) from the line.
  const geometry::Vec3 w{uy, -ux, 0}, bv{-sin_b * ux, -sin_b * uy, cos_b};
  const double pa = std::atan2(dot(na, w), dot(na, bv)), pb = std::atan2(dot(nb, w), dot(nb, bv));
  // A little wider than exact: at the band's ends the edge and facet contacts agree.
  const double margin = 1e-7;
  const double k2 = sin_b * sin_b;
  auto g = [&](double phi) {
    phi = std::clamp(phi, -0.5 * M_PI, 0.5 * M_PI);
    const double u = std::sin(phi), au = std::fabs(u);
    const double q = std::sqrt(au * au + k2 * (1 - au * au));
    const double d = c.rc > 0 ? (q > 0 ? au * (c.rk + c.rc / q) : c.R) : au * c.rk;
    return std::copysign(std::min(d, c.R), u);
  };
  EdgeBand band{g(std::min(pa, pb) - margin), g(std::max(pa, pb) + margin)};
  const double pad = 1e-7 * (1 + c.R);
  band.lo -= pad;
  band.hi += pad;
  if (band.lo <= -c.R && band.hi >= c.R) return {};
  return band;
}

ClPrimitives select_primitives(const geometry::Mesh& mesh, const CutterShape& cutter, bool skip_concave) {
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

  std::vector<geometry::MeshEdge> all = geometry::unique_edges(mesh);  // sorted by (a, b)
  out.edges_total = all.size();
  std::vector<std::uint8_t> drawn(all.size(), 1);
  std::vector<EdgeBand> bands;
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
    bands.assign(all.size(), EdgeBand{});
    for (std::size_t e = 0; e < all.size(); ++e) {
      if (all[e].uses != 2) continue;
      if (edge_is_redundant(mesh, cutter, all[e].a, all[e].b, slots[e])) {
        drawn[e] = 0;
        continue;
      }
      geometry::Vec3 na, nb;
      if (edge_is_convex(mesh, all[e].a, all[e].b, slots[e], na, nb))
        bands[e] = edge_band(mesh.vertices[all[e].a], mesh.vertices[all[e].b], na, nb, cutter);
    }
  }

  std::vector<std::uint8_t> covered(nv, 0);
  struct Drawn {
    std::array<std::uint32_t, 2> ab;
    EdgeBand band;
  };
  std::vector<Drawn> drawn_edges;
  for (std::size_t e = 0; e < all.size(); ++e) {
    if (!drawn[e]) continue;
    drawn_edges.push_back({{all[e].a, all[e].b}, bands.empty() ? EdgeBand{} : bands[e]});
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
  std::sort(drawn_edges.begin(), drawn_edges.end(), [&](const Drawn& dp, const Drawn& dq) {
    const auto& p = dp.ab;
    const auto& q = dq.ab;
    const double zp = std::fmax(V[p[0]].z, V[p[1]].z), zq = std::fmax(V[q[0]].z, V[q[1]].z);
    return zp != zq ? zp > zq : p < q;
  });
  out.edges.reserve(drawn_edges.size());
  out.edge_bands.reserve(drawn_edges.size());
  for (const auto& d : drawn_edges) {
    out.edges.push_back(d.ab);
    out.edge_bands.push_back(d.band);
  }
  std::sort(out.vertices.begin(), out.vertices.end(), [&](std::uint32_t p, std::uint32_t q) {
    return V[p].z != V[q].z ? V[p].z > V[q].z : p < q;
  });
  return out;
}

}  // namespace cncstream::cam::cl_detail
