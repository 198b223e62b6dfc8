#pragma once
// Indexed triangle soup. Vertices are welded on exact coordinate equality when
// loaded, so unique edges and vertices are cheap to enumerate; no other
// topology is assumed (non-manifold, holes and any winding are allowed).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "cncstream/geometry/vec3.hpp"

namespace cncstream::geometry {

struct Mesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;

  std::size_t size() const { return triangles.size(); }
  Vec3 corner(std::size_t t, int k) const { return vertices[triangles[t][k]]; }
  Box3 bounds() const;

  // Scale every coordinate by k (unit conversion, --scale).
  void scale(double k);
  // Translate every coordinate by d.
  void translate(const Vec3& d);
};

// Unique undirected edges, each as (lower index, higher index), with the
// number of triangles that use it.
struct MeshEdge {
  std::uint32_t a, b;
  std::uint32_t uses;
};
std::vector<MeshEdge> unique_edges(const Mesh& mesh);

// What a person wants to know about a loaded mesh.
struct MeshSummary {
  std::size_t facets = 0;
  std::size_t dropped_degenerate = 0;  // zero-area facets removed at load
  std::size_t vertices = 0;
  std::size_t edges = 0;
  std::size_t boundary_edges = 0;      // used by one facet
  std::size_t nonmanifold_edges = 0;   // used by three or more
  Box3 bounds;
  bool closed() const { return facets > 0 && boundary_edges == 0 && nonmanifold_edges == 0; }
  std::string to_string() const;
};
MeshSummary summarize(const Mesh& mesh, std::size_t dropped_degenerate = 0);

}  // namespace cncstream::geometry
