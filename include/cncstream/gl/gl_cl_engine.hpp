#pragma once
// The thesis's CL engine (chapter 3): every facet's offset for the cutter
// (face offset, edge offsets, vertex offsets; see offset_tessellation.hpp)
// tessellated to a chordal tolerance, rendered top-down with an orthographic
// camera into a 32-bit float depth buffer that keeps the highest value, and
// read back as the CL grid (tool tip heights). Pixel (i, j) is grid node
// (i, j): the same nodes, format and floor as the exact engine's ClGrid.
//
// Without trimming, every node is <= the exact engine's height (up to float
// rounding: measured <= 0.002 mm, see docs/PERFORMANCE.md) and >= it minus
// the tolerance, except at nodes right beside a vertical part of the exact
// surface (a vertex offset's rim, a wall): within the rasterizer's sub-pixel
// snap (1/256 pixel) a node inside the reach may be lit from a steeper
// triangle next to it, and within CutterCap::sliver_width() of a rim it may
// miss it. A node out of a vertex's, an edge's or a facet's XY reach (the
// cutter's radius) is never lit by it: each fragment checks its distance
// from the primitive (a margin of about 4e-6 of the primitive's size plus R
// inside the radius, for float rounding), so a node at exactly the radius
// gets what lies below, as a node just beyond it does. With `trim` (the
// thesis's bounding spaces, 3.4) each facet's edge and vertex offsets are
// clipped to the facet's vertical prism, which drops parts of the envelope:
// nodes can fall far below.
//
// Needs an OpenGL 3.3 core context through EGL (Mesa's surfaceless platform:
// llvmpipe without a GPU); throws GlError naming what failed when there is
// none.
#include <cstddef>
#include <optional>
#include <string>

#include "cncstream/cam/cl_grid.hpp"
#include "cncstream/cam/cutter.hpp"
#include "cncstream/geometry/mesh.hpp"
#include "cncstream/gl/gl_error.hpp"

namespace cncstream::gl {

struct GlClOptions {
  double tolerance = 0.05;        // chordal tolerance of the offset tessellation, mm
  bool trim = false;              // the thesis's bounding-space trimming
  std::optional<double> floor;    // height of untouched nodes; default the mesh's lowest z
  std::size_t max_tile = 0;       // framebuffer side in pixels; 0: the GL's limit, at most 4096
  bool skip_coplanar_edges = true; // leave out manifold edges between coplanar facets (their face offsets meet)
  int egl_platform = 0x31DD;      // EGL_PLATFORM_SURFACELESS_MESA
  // Raise every node off the floor by the tessellation's bound below the
  // exact surface and two depth steps, so none is below it (outside the rim
  // slivers): a grid to cut from rather than to compare.
  bool lift_to_bound = false;
};

struct GlClStats {
  std::string renderer;           // GL_RENDERER | GL_VERSION
  std::size_t face_offsets = 0, edges_drawn = 0, vertices_drawn = 0;
  std::size_t triangles = 0;      // rendered per tile
  std::size_t tiles = 0;
  std::size_t cap_spokes = 0, cap_rings = 0;
  double sliver_width = 0;        // mm, see CutterCap
  double height_error_bound = 0;  // mm, the tessellation's bound below the exact surface
  double depth_quantum = 0;       // mm, one step of the depth mapping near the top
  double lifted = 0;              // mm every node off the floor was raised (lift_to_bound)
};

// Throws std::invalid_argument for a bad spec or tolerance, GlError when no
// GL context can be made or used. Calls from several threads run one after
// the other (one EGL display per process).
cam::ClGrid compute_cl_grid_gl(const geometry::Mesh& mesh, const cam::Cutter& cutter, const cam::GridSpec& spec,
                          const GlClOptions& options = {}, GlClStats* stats = nullptr);

}  // namespace cncstream::gl
