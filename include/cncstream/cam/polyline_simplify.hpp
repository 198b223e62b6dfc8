#pragma once
// One-sided reduction of a sampled height profile z(s) (a tool path's CL
// along a pass) to fewer straight moves that are never below any sample (no
// gouge) and at most `tolerance` above any sample (bounded material left).
//
// simplify_profile_above keeps a subset of the samples as vertices, on the
// profile itself. Where the profile is convex (a ball rolling over an edge, a
// dome) every chord between samples dips below the samples between, so
// nothing merges. fit_profile_in_band lets each vertex sit anywhere in the
// band [z, z + tolerance] above its sample: a circumscribed polyline, whose
// moves on a convex stretch of radius R are about sqrt(8 R tolerance) long
// instead of the sample spacing. Both are linear in the samples: each anchor
// keeps the interval of slopes every sample since allows (a "sleeve").
#include <cstddef>
#include <vector>

namespace cncstream::cam {

// s must be strictly increasing; returns the indices of kept samples,
// always including the first and the last.
std::vector<std::size_t> simplify_profile_above(const std::vector<double>& s, const std::vector<double>& z,
                                                double tolerance);

struct BandVertex {
  std::size_t index = 0;  // the sample the vertex stands above
  double z = 0;           // in [z[index], z[index] + tolerance]; the first and last exactly on their samples
};

// The fewest vertices the greedy sleeve finds (with one move of look-ahead
// for where in its window each vertex sits) such that the polyline through
// them is within [z_k, z_k + tolerance] at every sample k. Between samples
// the polyline and the samples' own polyline are both straight, so it is
// within the band there too. s must be strictly increasing.
std::vector<BandVertex> fit_profile_in_band(const std::vector<double>& s, const std::vector<double>& z,
                                            double tolerance);

}  // namespace cncstream::cam
