// Height field -> closed triangle mesh (for STL export of machined stock).
#include "cncstream/cam/height_field_mesh.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "cncstream/geometry/stl.hpp"

namespace cncstream::cam {

geometry::Mesh height_field_solid(const GridSpec& g, std::span<const double> z, double bottom) {
  if (g.nx < 2 || g.ny < 2) throw std::invalid_argument("height field solid needs at least 2 x 2 nodes");
  if (z.size() != g.size())
    throw std::invalid_argument("height field solid: " + std::to_string(z.size()) + " values for a grid of " +
                                std::to_string(g.size()) + " nodes");
  if (g.size() * 2 + 1 > 0xffffffffu) throw std::invalid_argument("height field solid: grid too large for a mesh");
  for (std::size_t k = 0; k < z.size(); ++k) {
    if (!std::isfinite(z[k]))
      throw std::invalid_argument("height field solid: node " + std::to_string(k) + " has no height");
    if (!(bottom < z[k]))
      throw std::invalid_argument("height field solid: bottom " + std::to_string(bottom) +
                                  " is not below node " + std::to_string(k) + " at " + std::to_string(z[k]));
  }
  geometry::Mesh m;
  const auto top = [&](std::size_t i, std::size_t j) { return static_cast<std::uint32_t>(j * g.nx + i); };
  for (std::size_t j = 0; j < g.ny; ++j)
    for (std::size_t i = 0; i < g.nx; ++i) m.vertices.push_back({g.x(i), g.y(j), z[j * g.nx + i]});
  for (std::size_t j = 0; j + 1 < g.ny; ++j)
    for (std::size_t i = 0; i + 1 < g.nx; ++i) {
      const auto a = top(i, j), b = top(i + 1, j), c = top(i + 1, j + 1), d = top(i, j + 1);
      m.triangles.push_back({a, b, c});
      m.triangles.push_back({a, c, d});
    }
  // The boundary, counter-clockwise seen from above: south, east, north, west.
  std::vector<std::pair<std::size_t, std::size_t>> ring;
  for (std::size_t i = 0; i + 1 < g.nx; ++i) ring.emplace_back(i, 0);
  for (std::size_t j = 0; j + 1 < g.ny; ++j) ring.emplace_back(g.nx - 1, j);
  for (std::size_t i = g.nx - 1; i > 0; --i) ring.emplace_back(i, g.ny - 1);
  for (std::size_t j = g.ny - 1; j > 0; --j) ring.emplace_back(0, j);
  const auto base = static_cast<std::uint32_t>(m.vertices.size());
  for (const auto& [i, j] : ring) m.vertices.push_back({g.x(i), g.y(j), bottom});
  const auto centre = static_cast<std::uint32_t>(m.vertices.size());
  m.vertices.push_back({(g.x0 + g.x1()) / 2, (g.y0 + g.y1()) / 2, bottom});
  const auto n = static_cast<std::uint32_t>(ring.size());
  for (std::uint32_t k = 0; k < n; ++k) {
    const std::uint32_t q = (k + 1) % n;
    const auto tp = top(ring[k].first, ring[k].second), tq = top(ring[q].first, ring[q].second);
    const auto bp = base + k, bq = base + q;
    // Outside is to the right of P -> Q: (bP, bQ, tQ, tP) is counter-clockwise from there.
    m.triangles.push_back({bp, bq, tq});
    m.triangles.push_back({bp, tq, tp});
    m.triangles.push_back({centre, bq, bp});  // seen from below
  }
  return m;
}

void write_height_field_stl(const std::filesystem::path& path, const GridSpec& grid, std::span<const double> z,
                            double bottom) {
  geometry::write_stl_binary(path, height_field_solid(grid, z, bottom), "cncstream machined stock");
}

}  // namespace cncstream::cam
