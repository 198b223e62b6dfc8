#include "cncstream/geometry/mesh.hpp"

#include <algorithm>
#include <sstream>

namespace cncstream::geometry {

Box3 Mesh::bounds() const {
  Box3 b;
  for (const auto& t : triangles)
    for (auto idx : t) b.add(vertices[idx]);
  return b;
}

void Mesh::scale(double k) {
  for (auto& v : vertices) v *= k;
}

void Mesh::translate(const Vec3& d) {
  for (auto& v : vertices) v += d;
}

std::vector<MeshEdge> unique_edges(const Mesh& mesh) {
  // Sort-based rather than hashed: linear memory, cache-friendly, deterministic.
  std::vector<std::uint64_t> keys;
  keys.reserve(mesh.triangles.size() * 3);
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      std::uint32_t a = t[k], b = t[(k + 1) % 3];
      if (a == b) continue;
      if (a > b) std::swap(a, b);
      keys.push_back((std::uint64_t{a} << 32) | b);
    }
  }
  std::sort(keys.begin(), keys.end());
  std::vector<MeshEdge> edges;
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i;
    while (j < keys.size() && keys[j] == keys[i]) ++j;
    edges.push_back({static_cast<std::uint32_t>(keys[i] >> 32),
                     static_cast<std::uint32_t>(keys[i] & 0xffffffffu),
                     static_cast<std::uint32_t>(j - i)});
    i = j;
  }
  return edges;
}

MeshSummary summarize(const Mesh& mesh, std::size_t dropped_degenerate) {
  MeshSummary s;
  s.facets = mesh.triangles.size();
  s.dropped_degenerate = dropped_degenerate;
  s.bounds = mesh.bounds();
  std::vector<std::uint8_t> used(mesh.vertices.size(), 0);
  for (const auto& t : mesh.triangles)
    for (auto idx : t) used[idx] = 1;
  s.vertices = static_cast<std::size_t>(std::count(used.begin(), used.end(), 1));
  for (const auto& e : unique_edges(mesh)) {
    ++s.edges;
    if (e.uses == 1) ++s.boundary_edges;
    if (e.uses > 2) ++s.nonmanifold_edges;
  }
  return s;
}

std::string MeshSummary::to_string() const {
  std::ostringstream o;
  o << "facets: " << facets << " (" << dropped_degenerate << " zero-area dropped)\n";
  o << "vertices: " << vertices << ", edges: " << edges << "\n";
  if (bounds.empty()) {
    o << "bounds: empty\n";
  } else {
    const Vec3 sz = bounds.size();
    o << "bounds: x " << bounds.lo.x << " .. " << bounds.hi.x << ", y " << bounds.lo.y << " .. "
      << bounds.hi.y << ", z " << bounds.lo.z << " .. " << bounds.hi.z << "  (" << sz.x << " x "
      << sz.y << " x " << sz.z << " mm)\n";
  }
  o << "closed: " << (closed() ? "yes" : "no");
  if (!closed() && facets > 0)
    o << " (" << boundary_edges << " boundary edges, " << nonmanifold_edges << " non-manifold edges)";
  o << "\n";
  return o.str();
}

}  // namespace cncstream::geometry
