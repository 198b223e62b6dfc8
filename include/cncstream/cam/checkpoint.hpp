#pragma once
// Long computations of this layer (CL grids, raster paths, the cut
// simulation, reach limits) call a checkpoint between units of work with the
// fraction of that computation done, so that a caller can show progress and
// stop early. The checkpoint may throw: the exception leaves the computation
// (from a worker thread too; the parallel loop stops taking new work and
// rethrows it to the caller) and nothing half-computed is returned. It is
// called concurrently from worker threads, and fractions from different
// workers may arrive slightly out of order. An empty checkpoint costs nothing.
#include <functional>

namespace cncstream::cam {

using Checkpoint = std::function<void(double fraction_done)>;

// A step of a longer computation reporting into `whole` as [from, to] of it
// (empty when `whole` is). `whole` must outlive the result.
inline Checkpoint checkpoint_part(const Checkpoint& whole, double from, double to) {
  if (!whole) return {};
  return [&whole, from, to](double f) { whole(from + (to - from) * f); };
}

}  // namespace cncstream::cam
