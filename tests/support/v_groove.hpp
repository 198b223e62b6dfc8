#pragma once
// A known-answer part for rest machining and pencil passes: the top of a
// 40 x 20 block at z = 10 with a 90-degree V-groove along Y, its walls from
// x = 16 and x = 24 down to the crease at x = 20, z = 6 (an open surface).
// A ball of radius r in it stops r (sqrt 2 - 1) above the crease.
#include <cstdint>

#include "cncstream/geometry/mesh.hpp"

namespace cncstream::test {

inline geometry::Mesh v_groove() {
  geometry::Mesh m;
  const double xs[] = {0, 16, 20, 24, 40}, zs[] = {10, 10, 6, 10, 10};
  for (int k = 0; k < 5; ++k) {
    m.vertices.push_back({xs[k], 0, zs[k]});
    m.vertices.push_back({xs[k], 20, zs[k]});
  }
  for (std::uint32_t k = 0; k < 4; ++k) {
    const std::uint32_t a = 2 * k;
    m.triangles.push_back({a, a + 2, a + 3});
    m.triangles.push_back({a, a + 3, a + 1});
  }
  return m;
}

}  // namespace cncstream::test
