#pragma once
// Small meshes built in code for the CL engine tests.
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <random>
#include <tuple>
#include <vector>

#include "cncstream/geometry/mesh.hpp"

namespace cl_test {

using cncstream::geometry::Mesh;
using cncstream::geometry::Vec3;

// Each triangle with its own three vertices (nothing shared).
inline Mesh soup(const std::vector<std::array<Vec3, 3>>& tris) {
  Mesh m;
  for (const auto& t : tris) {
    const auto base = static_cast<std::uint32_t>(m.vertices.size());
    for (const auto& p : t) m.vertices.push_back(p);
    m.triangles.push_back({base, base + 1, base + 2});
  }
  return m;
}

// Welds equal coordinates, like the STL loader.
inline Mesh welded(const std::vector<std::array<Vec3, 3>>& tris) {
  Mesh m;
  std::map<std::tuple<double, double, double>, std::uint32_t> index;
  for (const auto& t : tris) {
    std::array<std::uint32_t, 3> f{};
    for (int k = 0; k < 3; ++k) {
      const auto key = std::make_tuple(t[k].x, t[k].y, t[k].z);
      auto [it, fresh] = index.emplace(key, static_cast<std::uint32_t>(m.vertices.size()));
      if (fresh) m.vertices.push_back(t[k]);
      f[k] = it->second;
    }
    m.triangles.push_back(f);
  }
  return m;
}

// Closed axis-aligned box, mixed winding on purpose.
inline Mesh box(Vec3 lo, Vec3 hi) {
  const Vec3 c[8] = {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {lo.x, hi.y, lo.z},
                     {lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}};
  const int q[6][4] = {{0, 1, 2, 3}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  std::vector<std::array<Vec3, 3>> t;
  for (int k = 0; k < 6; ++k) {
    t.push_back({c[q[k][0]], c[q[k][1]], c[q[k][2]]});
    t.push_back({c[q[k][0]], c[q[k][3]], c[q[k][2]]});  // opposite winding
  }
  return welded(t);
}

// Height field z = f(x, y) on an n x n quad grid over [x0, x0+size]^2, each
// quad split along an alternating diagonal; welded (manifold inside).
inline Mesh terrain(double x0, double y0, double size, int n, const std::function<double(double, double)>& f) {
  std::vector<std::array<Vec3, 3>> t;
  auto P = [&](int i, int j) {
    const double x = x0 + size * i / n, y = y0 + size * j / n;
    return Vec3{x, y, f(x, y)};
  };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      if ((i + j) % 2) {
        t.push_back({P(i, j), P(i + 1, j), P(i + 1, j + 1)});
        t.push_back({P(i, j), P(i + 1, j + 1), P(i, j + 1)});
      } else {
        t.push_back({P(i, j), P(i + 1, j), P(i, j + 1)});
        t.push_back({P(i + 1, j), P(i + 1, j + 1), P(i, j + 1)});
      }
    }
  return welded(t);
}

// A spherical cap on a plate at z = 2 over [0, size]^2: the sphere of radius r
// centred on the square, cut at half its radius, so the cap meets the plate
// in a 60-degree crease (0.25 mm quads).
inline Mesh dome_on_plate(double size, double r) {
  return terrain(0, 0, size, static_cast<int>(std::lround(size * 4)), [size, r](double x, double y) {
    const double d = std::hypot(x - size / 2, y - size / 2);
    return 2 + std::max(0.0, std::sqrt(std::max(0.0, r * r - d * d)) - r / 2);
  });
}

// Upper hemisphere of radius r centred at the origin, vertices on the sphere.
inline Mesh hemisphere(double r, int rings, int sectors) {
  std::vector<std::array<Vec3, 3>> t;
  const double pi = std::acos(-1.0);
  auto P = [&](int ring, int s) {
    if (ring == 0) return Vec3{0, 0, r};
    const double th = (pi / 2) * ring / rings, ph = 2 * pi * (s % sectors) / sectors;
    return Vec3{r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph), r * std::cos(th)};
  };
  for (int ring = 0; ring < rings; ++ring)
    for (int s = 0; s < sectors; ++s) {
      if (ring == 0) {
        t.push_back({P(0, 0), P(1, s), P(1, s + 1)});
      } else {
        t.push_back({P(ring, s), P(ring + 1, s), P(ring + 1, s + 1)});
        t.push_back({P(ring, s), P(ring + 1, s + 1), P(ring, s + 1)});
      }
    }
  return welded(t);
}

}  // namespace cl_test
