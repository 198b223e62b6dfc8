// The depth-buffer CL engine at the edge of the cutter's reach: a node at
// exactly the radius from a vertex, an edge or a vertical wall, and nodes
// just beyond it (5e-5 mm, the held-out part's corner, and 1e-3 mm), against
// the exact engine. A node out of reach must not be raised by the primitive
// (the rasterizer's sub-pixel snapping once lit it from the rim of the
// vertex's or edge's offset, up to the part's height above the exact value);
// a node at exactly the reach may take either side's value. Every cutter
// kind: flat, ball, bull-nose and the tapered ball (a band profile).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/gl/gl_cl_engine.hpp"

using namespace cncstream;

namespace {

constexpr double kAbove = 2e-3;   // float rounding (test_gl_cl_engine.cpp)
constexpr double kTolerance = 0.05;
constexpr double kStep = 0.4;
constexpr std::size_t kSpacing = 40;  // nodes between probes: 16 mm, beyond every item's reach
const double kAngles[] = {0.0, 0.37, M_PI / 4, 2.1};
const double kBeyond[] = {0.0, 5e-5, 1e-3};  // distance beyond the reach

struct Probe {
  std::size_t i = 0, j = 0;
  double beyond = 0;   // how far beyond the reach the node is
  double nx = 0, ny = 0;  // unit direction from the primitive to the node
};

// Adds an item for a node at (x, y), its primitive `dist` away in direction
// -(nx, ny), the item itself farther away still.
using Item = std::function<void(geometry::Mesh&, double x, double y, double nx, double ny, double dist)>;

void add_triangle(geometry::Mesh& m, const geometry::Vec3& a, const geometry::Vec3& b, const geometry::Vec3& c) {
  const auto k = static_cast<std::uint32_t>(m.vertices.size());
  m.vertices.insert(m.vertices.end(), {a, b, c});
  m.triangles.push_back({k, k + 1, k + 2});
}

// A steep triangle whose apex (5 mm high) is the nearest point to the node.
void vertex_item(geometry::Mesh& m, double x, double y, double nx, double ny, double dist) {
  const geometry::Vec3 apex{x - dist * nx, y - dist * ny, 5};
  const geometry::Vec3 back{apex.x - 3 * nx, apex.y - 3 * ny, 0}, side{-ny * 1.5, nx * 1.5, 0};
  add_triangle(m, apex, back + side, back - side);
}

// A vertical fence whose top edge rises from 3 to 6 mm along it: the node is
// beside the edge's middle, `dist` from it and from the wall below.
void edge_item(geometry::Mesh& m, double x, double y, double nx, double ny, double dist) {
  const geometry::Vec3 c{x - dist * nx, y - dist * ny, 0}, t{-ny * 2, nx * 2, 0};
  const geometry::Vec3 b0 = c - t, b1 = c + t, t0 = b0 + geometry::Vec3{0, 0, 3}, t1 = b1 + geometry::Vec3{0, 0, 6};
  add_triangle(m, b0, b1, t1);
  add_triangle(m, b0, t1, t0);
}

// A box 5 mm high whose corner is the nearest point to the node (the
// held-out part's case): its two walls meet there, one along (nx, ny)
// rotated by 30 degrees.
void corner_item(geometry::Mesh& m, double x, double y, double nx, double ny, double dist) {
  const double a = std::atan2(ny, nx) + M_PI / 6;  // the box lies in the quadrant beyond the corner
  const geometry::Vec3 u{-std::cos(a), -std::sin(a), 0}, v{-std::cos(a - M_PI / 2), -std::sin(a - M_PI / 2), 0};
  const geometry::Vec3 c{x - dist * nx, y - dist * ny, 0};
  // u and v point away from the node (the node sees the corner from outside).
  const geometry::Vec3 p[4] = {c, c + u * 3, c + u * 3 + v * 3, c + v * 3};
  const geometry::Vec3 h{0, 0, 5};
  add_triangle(m, p[0] + h, p[1] + h, p[2] + h);
  add_triangle(m, p[0] + h, p[2] + h, p[3] + h);
  for (int k = 0; k < 4; ++k) {
    const geometry::Vec3 a0 = p[k], a1 = p[(k + 1) % 4];
    add_triangle(m, a0, a1, a1 + h);
    add_triangle(m, a0, a1 + h, a0 + h);
  }
}

struct Layout {
  geometry::Mesh mesh;
  cam::GridSpec spec;
  std::vector<Probe> probes;
};

Layout lay_out(const Item& item, double R) {
  Layout l;
  const std::size_t cols = std::size(kAngles), rows = std::size(kBeyond);
  l.spec.x0 = 0;
  l.spec.y0 = 0;
  l.spec.dx = l.spec.dy = kStep;
  l.spec.nx = (cols + 1) * kSpacing;
  l.spec.ny = (rows + 1) * kSpacing;
  for (std::size_t r = 0; r < rows; ++r)
    for (std::size_t c = 0; c < cols; ++c) {
      Probe p;
      p.i = (c + 1) * kSpacing;
      p.j = (r + 1) * kSpacing;
      p.beyond = kBeyond[r];
      p.nx = std::cos(kAngles[c]);
      p.ny = std::sin(kAngles[c]);
      item(l.mesh, l.spec.x(p.i), l.spec.y(p.j), p.nx, p.ny, R + p.beyond);
      l.probes.push_back(p);
    }
  return l;
}

void check_reach(const Item& item, const char* what) {
  // The tapered ball's rim is 12.9 mm above its tip: at exactly the reach
  // the exact engine's touch is below the floor.
  for (const char* spec : {"ball:3.175", "flat:6", "bull:6:1", "taper:1:5:3.175"}) {
    SCOPED_TRACE(std::string(what) + " " + spec);
    const cam::Cutter c = cam::parse_cutter_spec(spec);
    const Layout l = lay_out(item, c.radius);
    const cam::ClEngine exact(l.mesh, c);
    gl::GlClOptions o;
    o.tolerance = kTolerance;
    o.floor = 0;
    const cam::ClGrid g = gl::compute_cl_grid_gl(l.mesh, c, l.spec, o);
    std::size_t touched_at_reach = 0;
    for (const Probe& p : l.probes) {
      const double x = l.spec.x(p.i), y = l.spec.y(p.j);
      const double e = exact.height_at(x, y), v = g.at(p.i, p.j);
      SCOPED_TRACE(testing::Message() << "node " << p.i << "," << p.j << " (" << p.beyond << " mm beyond the reach, "
                                      << "direction " << p.nx << "," << p.ny << "): exact " << e << ", GL " << v);
      if (p.beyond > 0) {
        EXPECT_LE(v, e + kAbove);
        // Out of reach: the exact engine's value (here the floor), not the
        // rim of the offset.
        EXPECT_GE(v, e - kTolerance - kAbove);
      } else {
        // At the reach (a tangency: the cutter cannot cut into the
        // primitive there at any height): the value of either side, the
        // rim's touch or what a node a micron farther out gets.
        const double out = exact.height_at(x + 1e-3 * p.nx, y + 1e-3 * p.ny);
        EXPECT_LE(v, std::max(e, out) + kAbove);
        EXPECT_GE(v, std::min(e, out) - kTolerance - kAbove);
        if (std::fabs(e - out) > 1) ++touched_at_reach;
      }
    }
    // The exact engine touches some of them there (others are a rounding
    // beyond): the tangent case is tested.
    EXPECT_GT(touched_at_reach, 0u);
  }
}

TEST(GlClReach, NodesAtAndJustBeyondTheReachOfAVertex) { check_reach(vertex_item, "vertex"); }
TEST(GlClReach, NodesAtAndJustBeyondTheReachOfAnEdge) { check_reach(edge_item, "edge"); }
TEST(GlClReach, NodesAtAndJustBeyondTheReachOfAWallCorner) { check_reach(corner_item, "corner"); }

}  // namespace
