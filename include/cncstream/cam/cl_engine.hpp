#pragma once
// The CL engine: for a mesh and a cutter, the tool-tip height at which the
// cutter touches the mesh from above without penetrating it anywhere. This is
// the upper envelope of the face, edge and vertex offsets of every facet (the
// thesis's offset surface seen through a depth buffer), computed exactly.
#include <cstddef>
#include <functional>
#include <memory>
#include <optional>

#include "cncstream/cam/checkpoint.hpp"
#include "cncstream/cam/cl_grid.hpp"
#include "cncstream/cam/cutter.hpp"
#include "cncstream/cam/sampled_line.hpp"
#include "cncstream/geometry/mesh.hpp"

namespace cncstream::cam {

struct ClOptions {
  // Height for nodes the cutter cannot touch; default: the mesh's lowest z.
  std::optional<double> floor;
  // The floor is also the lowest the tip goes: a touched node whose contact
  // lies below it comes out at the floor. A job's part rests on its floor
  // (below it is the fixture); a cutter touches the top rim of a wall lower
  // than its flutes from as far as its reach, its tip that far below the rim
  // (a 3.175 mm tapered ball's flutes end 12.9 mm above its tip: 9.9 mm
  // below the plaque's 3 mm base). Raising a tip never gouges. Off (the CL
  // surface itself, below the floor where it is): clgrid and the oracles.
  bool floor_is_lowest = false;
  // Worker threads: 0 = the caller's oneTBB task arena (the shared pool of all
  // cores unless the caller limited it); n = a task arena of n slots.
  unsigned threads = 0;
  // Upper bound on the bytes of grid held at once by compute_tiles().
  std::size_t max_tile_bytes = std::size_t{256} << 20;
  // Leave out manifold edges where the surface is a valley or flat: for a
  // convex cutter they never raise the envelope (the adjacent facets' own
  // contacts cover them). Off draws every unique edge; tests compare both.
  bool skip_concave_edges = true;
};

// What the engine draws for a mesh (for benchmarks and diagnostics).
struct ClEngineStats {
  std::size_t facets = 0;
  std::size_t face_offsets = 0;   // non-vertical facets with an interior contact
  std::size_t edges = 0;          // unique edges of the mesh
  std::size_t edges_drawn = 0;    // after leaving out valley / coplanar ones
  std::size_t vertices = 0;       // vertices used by some facet
  std::size_t vertices_drawn = 0; // those not covered by a drawn edge
};

// A rectangular block of a grid: rows [j0, j0 + spec.ny) of the full grid.
struct ClTile {
  std::size_t j0 = 0;
  ClGrid grid;  // grid.spec covers only this tile's rows
};

// The engine keeps a reference to the mesh, which must outlive it (a
// temporary mesh is rejected at compile time). Construction is O(mesh); every
// query is const and may run concurrently.
class ClEngine {
 public:
  ClEngine(const geometry::Mesh& mesh, const Cutter& cutter, ClOptions options = {});
  ClEngine(geometry::Mesh&& mesh, const Cutter& cutter, ClOptions options = {}) = delete;
  ~ClEngine();
  ClEngine(ClEngine&&) noexcept;
  ClEngine& operator=(ClEngine&&) noexcept;

  const Cutter& cutter() const;
  double floor() const;
  const ClEngineStats& stats() const;

  // Whole grid in memory. Throws std::invalid_argument for a bad spec
  // (non-positive or non-finite step, non-finite origin). `checkpoint` is
  // called after each tile of nodes (see checkpoint.hpp).
  ClGrid compute(const GridSpec& spec, const Checkpoint& checkpoint = {}) const;
  // Grid in row tiles of at most options.max_tile_bytes each, handed to sink
  // in order, so a grid larger than memory can be streamed to a file. Node
  // heights are identical to compute()'s (nodes are placed from the full
  // spec); a tile's own spec.y0 is spec.y(j0). `checkpoint` gets the
  // fraction of the whole grid done, inside each tile too.
  void compute_tiles(const GridSpec& spec, const std::function<void(const ClTile&)>& sink,
                     const Checkpoint& checkpoint = {}) const;
  // One point (drop-cutter query), same result as a grid node at (x, y);
  // the floor where nothing is touched. Builds a bucket index on first use.
  double height_at(double x, double y) const;
  // As height_at, but reports whether any facet was touched.
  double height_at(double x, double y, bool& on_floor) const;
  // The first k in [k0, k1] whose point on `line` has height_at above
  // `limit`; k1 + 1 if none has. The same answer as asking height_at point
  // by point, from fewer evaluations: a primitive that cannot rise above the
  // limit anywhere among a cell's points is passed over once for all of
  // them (the waterlines check every chord every 0.01 mm).
  std::size_t first_above(const SampledLine& line, std::size_t k0, std::size_t k1, double limit) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cncstream::cam
