#pragma once
// One-sided simplification of a sampled height profile z(s): keeps a subset
// of the samples as vertices so that the straight chords between kept
// vertices are never below any sample (no gouge) and at most `tolerance`
// above any sample (bounded material left). Linear time: each anchor keeps
// the interval of slopes every sample since it allows (a "sleeve").
#include <cstddef>
#include <vector>

namespace cncstream {

// s must be strictly increasing; returns the indices of kept samples,
// always including the first and the last.
std::vector<std::size_t> simplify_profile_above(const std::vector<double>& s, const std::vector<double>& z,
                                                double tolerance);

}  // namespace cncstream
