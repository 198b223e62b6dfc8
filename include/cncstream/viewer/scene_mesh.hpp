#pragma once
// The viewer's shaded surfaces as GPU-ready triangles, pure (no GL): the
// part (flat-shaded facets), a simulated cut coloured by its deviation from
// the design (the deviation map's colours, image/deviation_map.hpp), and the
// cutter as a solid of revolution at its tip.
#include <cstdint>
#include <vector>

#include "cncstream/cam/cl_grid.hpp"
#include "cncstream/cam/cutter.hpp"
#include "cncstream/cam/deviation.hpp"
#include "cncstream/geometry/mesh.hpp"
#include "cncstream/image/image.hpp"

namespace cncstream::viewer {

struct MeshVertex {  // 28 bytes
  float x = 0, y = 0, z = 0;
  float nx = 0, ny = 0, nz = 1;
  std::uint8_t r = 0, g = 0, b = 0, a = 255;
};

struct TriangleMesh {
  std::vector<MeshVertex> vertices;
  std::vector<std::uint32_t> indices;  // 3 per triangle
  geometry::Box3 bounds;
  std::size_t triangles() const { return indices.size() / 3; }
};

inline constexpr image::Rgb kPartColour{120, 150, 190};
inline constexpr image::Rgb kCutterColour{150, 150, 162};

// One vertex per facet corner with the facet's normal (any winding: the
// shader lights both sides).
TriangleMesh part_surface(const geometry::Mesh& mesh, image::Rgb colour = kPartColour);

// How much of the cutter is drawn above its tip: three diameters, at least 8 mm.
double default_cutter_length(const cam::Cutter& cutter);

// The cutter with its tip at `tip`: the profile (flat bottom, corner, or
// ball) swept around +Z, the side wall up `length` mm above the tip (0:
// default_cutter_length), and a top disc. `segments` around the axis.
TriangleMesh cutter_surface(const cam::Cutter& cutter, const geometry::Vec3& tip, double length = 0, int segments = 32);

struct CutSurface {
  TriangleMesh mesh;
  cam::DeviationStats stats;  // as cncsim verify reports them
};

// A machined height field (cncsim --result; NaN = no value) as its top
// surface, each node coloured by machined - design with the deviation
// map's scale (DeviationScale): gouges red, excess blue, within the
// tolerance pale green, off the design grey. Throws std::invalid_argument
// for a size mismatch or a grid smaller than 2 x 2.
CutSurface cut_surface(const cam::GridSpec& grid, const std::vector<float>& heights, const geometry::Mesh& design, double tolerance);
// As above with the design's heights on `grid` already sampled (a live cut
// redrawn many times over one grid samples the design once).
CutSurface cut_surface(const cam::GridSpec& grid, const std::vector<float>& heights, const cam::DesignHeights& design,
                       double tolerance);

// A stock's top surface without a design to compare with: one colour, shaded.
inline constexpr image::Rgb kStockColour{214, 188, 146};
TriangleMesh stock_surface(const cam::GridSpec& grid, const std::vector<float>& heights, image::Rgb colour = kStockColour);

}  // namespace cncstream::viewer
