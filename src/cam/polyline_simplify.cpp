#include "cncstream/cam/polyline_simplify.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace cncstream {

std::vector<std::size_t> simplify_profile_above(const std::vector<double>& s, const std::vector<double>& z,
                                                double tolerance) {
  if (s.size() != z.size()) throw std::invalid_argument("simplify_profile_above: size mismatch");
  const std::size_t n = s.size();
  std::vector<std::size_t> kept;
  if (n == 0) return kept;
  kept.push_back(0);
  if (n == 1) return kept;
  // Floating-point slack so that exactly collinear samples merge.
  const double eps = 1e-9;
  std::size_t anchor = 0;
  while (anchor + 1 < n) {
    double lo = -std::numeric_limits<double>::infinity();
    double hi = std::numeric_limits<double>::infinity();
    std::size_t last_ok = anchor + 1;  // the next sample is always a valid end
    for (std::size_t i = anchor + 1; i < n; ++i) {
      const double ds = s[i] - s[anchor];
      const double slope = (z[i] - z[anchor]) / ds;
      // i is a valid end if the chord anchor->i clears all samples in between.
      if (i > anchor + 1) {
        if (slope < lo - eps / ds || slope > hi + eps / ds) break;
      }
      last_ok = i;
      // Constraints sample i puts on any later chord from the anchor.
      lo = std::fmax(lo, slope);
      hi = std::fmin(hi, (z[i] + tolerance - z[anchor]) / ds);
      if (lo > hi + eps / ds) break;
    }
    kept.push_back(last_ok);
    anchor = last_ok;
  }
  return kept;
}

}  // namespace cncstream
