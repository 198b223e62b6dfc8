#include "cncstream/gl/boundary_nodes.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace cncstream::gl {

double exact_height_around(const cam::ClEngine& exact, double x, double y, double r, bool highest) {
  constexpr int kPoints = 32;
  double best = highest ? -HUGE_VAL : HUGE_VAL;
  for (int k = 0; k < kPoints; ++k) {
    const double th = 2 * std::numbers::pi * k / kPoints;
    bool untouched = false;
    double z = exact.height_at(x + r * std::cos(th), y + r * std::sin(th), untouched);
    if (untouched && !highest) z = -HUGE_VAL;
    best = highest ? std::max(best, z) : std::min(best, z);
  }
  return best;
}

}  // namespace cncstream::gl
