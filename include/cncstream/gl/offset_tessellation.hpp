#pragma once
// The thesis's offset surfaces (chapter 3) as triangles, for the depth-buffer
// CL engine. Pure geometry, no GL. Every cutter (cutter.hpp): the generalized
// APT ones in closed form, V-bits and tapered balls from their bands (the
// cap's rings then include each band's ends, so a kink is a ring).
//
// Every primitive's offset is the top of a convex solid: the primitive (a
// point, a segment, a facet) Minkowski-summed with the inverted cutter -C,
// whose top is z = -h(rho) over the disc rho <= R (tip at the origin). The
// cap below is a convex polytope P whose vertices lie ON that top surface
// (inscribed), so:
//   vertex offset  = P translated to the vertex (the sphere / vertex torus /
//                    flat disc),
//   edge offset    = the top of segment + (-C): the vertex offsets at both
//                    ends and, between, parallelograms between generators
//                    of the exact surface (the cylinder / swept torus / swept
//                    disc; edge_generators),
//   face offset    = the facet moved by the thesis's offset vector (eq. 3.3),
//                    exact.
// The top of a polytope inscribed in a convex solid is never above the
// solid's top, so every rendered height is <= the exact one. The rings and
// spokes of P are chosen so that, over P's own shadow, it is at most
// `tolerance` below (radial chords <= tolerance/2, angular chords <=
// tolerance/2). Where the exact surface is vertical (the rim of a vertex
// disc) P's shadow is an inscribed polygon of the exact shadow: a node in
// that sliver (at most sliver_width() wide) gets its height from whatever
// lies below instead.
//
// The edge offsets are not swept from P (P's rim polygon, swept along a
// sloping edge, falls short of the disc along the edge by up to
// sqrt(2 R sliver), which the slope turns into height): each edge gets its own
// generators on the exact surface (edge_generators).
#include <array>
#include <cstddef>
#include <vector>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/geometry/vec3.hpp"

namespace cncstream::gl {

// The inscribed cap P of the inverted cutter's top, as a polar grid: a centre
// point, rings at radii rho[k] (the last at R), `spokes` points per ring.
class CutterCap {
 public:
  CutterCap(const cam::Cutter& cutter, double tolerance);

  std::size_t spokes() const { return spokes_; }
  const std::vector<double>& ring_radius() const { return rho_; }   // increasing, last = R
  const std::vector<double>& ring_height() const { return z_; }     // -h(rho), <= 0
  // Points: [0] the centre, then ring k's spoke j at 1 + k * spokes + j.
  const std::vector<geometry::Vec3>& points() const { return points_; }
  // Top triangles (counter-clockwise seen from above), indices into points().
  const std::vector<std::array<std::uint32_t, 3>>& triangles() const { return triangles_; }
  // Widest gap between P's shadow and the exact disc of radius R.
  double sliver_width() const;
  // The largest vertical distance of P's top below the exact top over P's
  // shadow (bound, from the construction).
  double height_error_bound() const { return height_error_bound_; }

  // Edges of P (point index pairs) on its silhouette along direction d: the
  // edges whose two faces (the vertical side wall below the rim counts) face
  // opposite sides of d.
  // Their parallelograms swept along a segment parallel to d, with P at both
  // ends, bound the segment's offset from above.
  void silhouette_edges(const geometry::Vec3& d, std::vector<std::array<std::uint32_t, 2>>& out) const;

 private:
  struct CapEdge {
    std::uint32_t p, q;      // points
    std::uint32_t f1, f2;    // faces (index into face_normal_)
  };
  std::size_t spokes_ = 0;
  std::vector<double> rho_, z_;
  std::vector<geometry::Vec3> points_;
  std::vector<std::array<std::uint32_t, 3>> triangles_;
  std::vector<geometry::Vec3> face_normal_;  // per polar cell (fan triangle or quad), then the side wall per rim edge
  std::vector<CapEdge> edges_;
  double R_ = 0;
  double height_error_bound_ = 0;
};

// The edge offset of segment a-b: a ruled surface whose generators run
// parallel to the segment (for each lateral offset d from the segment's XY
// line, the height rises along it with the segment's slope), its cross
// section F(d) = max_u (-m u - h(sqrt(d^2 + u^2))) concave in d. Returns the
// points q_k (offsets from a point of the segment, on the inverted cutter's
// top) of generators at lateral offsets from -R to R, sampled so that the
// chords of F are at most `tolerance` below it; the parallelograms between
// consecutive generators, from a + q_k to b + q_k, are the edge offset's
// tessellation (the ends beyond them are the vertex offsets'). Empty for a
// vertical segment (its offset is its upper vertex's).
void edge_generators(const cam::Cutter& cutter, const geometry::Vec3& a, const geometry::Vec3& b, double tolerance, std::vector<geometry::Vec3>& out);

// The thesis's face offset (eq. 3.3) of a facet for the tool tip: the facet
// moved by rk * n + rc * n_xy / |n_xy| - rk * z, n its upward unit normal.
// For a band profile (V-bit, tapered ball, grown ones) the same idea: moved
// rho along n_xy / |n_xy| and h(rho) down, rho where the profile's tilt
// matches the facet's (the maximum of t rho - h(rho), t its slope).
// false for a (near-)vertical facet (n_z < 1e-8), whose offset is seen only
// through its edges and vertices.
bool face_offset_triangle(const geometry::Vec3& p0, const geometry::Vec3& p1, const geometry::Vec3& p2, const cam::Cutter& cutter,
                          std::array<geometry::Vec3, 3>& out);

// Upward unit normal of a triangle (n_z >= 0); zero for a degenerate one.
geometry::Vec3 upward_unit_normal(const geometry::Vec3& p0, const geometry::Vec3& p1, const geometry::Vec3& p2);

}  // namespace cncstream::gl
