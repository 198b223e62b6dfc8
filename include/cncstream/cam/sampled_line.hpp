#pragma once
// Points spaced evenly along a straight XY line, each placed by one formula
// so a caller and the CL engine's batched queries (ClEngine::first_above)
// compute the same point bit for bit.
#include <cstddef>

namespace cncstream::cam {

struct SampledLine {
  double ax = 0, ay = 0, bx = 0, by = 0;  // the line from a to b
  std::size_t n = 1;                       // point k at k / n of the way
  double ox = 0, oy = 0;                   // every point moved by this

  double x(std::size_t k) const { return ax + (bx - ax) * (double(k) / double(n)) + ox; }
  double y(std::size_t k) const { return ay + (by - ay) * (double(k) / double(n)) + oy; }
};

}  // namespace cncstream::cam
