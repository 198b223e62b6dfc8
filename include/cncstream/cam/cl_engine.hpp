#pragma once
// The CL engine: for a mesh and a cutter, the tool-tip height at which the
// cutter touches the mesh from above without penetrating it anywhere. This is
// the upper envelope of the face, edge and vertex offsets of every facet (the
// thesis's offset surface seen through a depth buffer), computed exactly.
#include <cstddef>
#include <functional>
#include <memory>
#include <optional>

#include "cncstream/cam/cl_grid.hpp"
#include "cncstream/cam/cutter.hpp"
#include "cncstream/geometry/mesh.hpp"

namespace cncstream {

struct ClOptions {
  // Height for nodes the cutter cannot touch; default: the mesh's lowest z.
  std::optional<double> floor;
  // Worker threads; 0 = hardware concurrency.
  unsigned threads = 0;
  // Upper bound on the bytes of grid held at once by compute_tiles().
  std::size_t max_tile_bytes = std::size_t{256} << 20;
};

// A rectangular block of a grid: rows [j0, j0 + spec.ny) of the full grid.
struct ClTile {
  std::size_t j0 = 0;
  ClGrid grid;  // grid.spec covers only this tile's rows
};

class ClEngine {
 public:
  ClEngine(const Mesh& mesh, const Cutter& cutter, ClOptions options = {});
  ~ClEngine();
  ClEngine(ClEngine&&) noexcept;
  ClEngine& operator=(ClEngine&&) noexcept;

  const Cutter& cutter() const;
  double floor() const;

  // Whole grid in memory.
  ClGrid compute(const GridSpec& spec) const;
  // Grid in row tiles of at most options.max_tile_bytes each, handed to sink
  // in order, so a grid larger than memory can be streamed to a file.
  void compute_tiles(const GridSpec& spec, const std::function<void(const ClTile&)>& sink) const;
  // One point (drop-cutter query), same result as a grid node at (x, y).
  double height_at(double x, double y) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cncstream
