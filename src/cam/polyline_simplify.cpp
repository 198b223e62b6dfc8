#include "cncstream/cam/polyline_simplify.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace cncstream::cam {

namespace {
// Floating-point slack so that exactly collinear samples merge.
constexpr double kEps = 1e-9;
}  // namespace

std::vector<std::size_t> simplify_profile_above(const std::vector<double>& s, const std::vector<double>& z,
                                                double tolerance) {
  if (s.size() != z.size()) throw std::invalid_argument("simplify_profile_above: size mismatch");
  const std::size_t n = s.size();
  std::vector<std::size_t> kept;
  if (n == 0) return kept;
  kept.push_back(0);
  if (n == 1) return kept;
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
        if (slope < lo - kEps / ds || slope > hi + kEps / ds) break;
      }
      last_ok = i;
      // Constraints sample i puts on any later chord from the anchor.
      lo = std::fmax(lo, slope);
      hi = std::fmin(hi, (z[i] + tolerance - z[anchor]) / ds);
      if (lo > hi + kEps / ds) break;
    }
    kept.push_back(last_ok);
    anchor = last_ok;
  }
  return kept;
}

namespace {

// How far one straight move from (s[a], za) can go inside the band: the
// last sample it can end above, and the slopes that reach it with every
// sample between inside the band. The last sample's band is closed to its
// own height (the profile's ends are pinned).
struct Reach {
  std::size_t last = 0;
  double lo = 0, hi = 0;
};

Reach reach_in_band(const std::vector<double>& s, const std::vector<double>& z, double tolerance, std::size_t a,
                    double za) {
  const std::size_t n = s.size();
  Reach r{a + 1, -std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  for (std::size_t i = a + 1; i < n; ++i) {
    const double ds = s[i] - s[a];
    const double top = i + 1 == n ? z[i] : z[i] + tolerance;
    const double lo = std::fmax(r.lo, (z[i] - za) / ds);
    const double hi = std::fmin(r.hi, (top - za) / ds);
    // The first sample is always reachable (za is inside its own band).
    if (i > a + 1 && lo > hi + kEps / ds) break;
    r.last = i;
    r.lo = lo;
    r.hi = std::fmax(lo, hi);
  }
  return r;
}

}  // namespace

std::vector<BandVertex> fit_profile_in_band(const std::vector<double>& s, const std::vector<double>& z,
                                            double tolerance) {
  if (s.size() != z.size()) throw std::invalid_argument("fit_profile_in_band: size mismatch");
  if (!(tolerance >= 0)) throw std::invalid_argument("fit_profile_in_band: tolerance must not be negative");
  const std::size_t n = s.size();
  std::vector<BandVertex> out;
  if (n == 0) return out;
  out.push_back({0, z[0]});
  if (n == 1) return out;
  std::size_t a = 0;
  double za = z[0];
  Reach r = reach_in_band(s, z, tolerance, a, za);
  for (;;) {
    const std::size_t j = r.last;
    const double ds = s[j] - s[a];
    if (j + 1 == n) {
      out.push_back({j, z[j]});
      break;
    }
    // Where in its window the vertex sits decides how far the next move
    // reaches: try a few heights, keep the farthest (the middle on ties:
    // it leaves room either way for the move after).
    constexpr int kCandidates = 5;
    constexpr int kOrder[kCandidates] = {2, 1, 3, 0, 4};
    double best_z = 0;
    Reach best{};
    bool have = false;
    for (int c : kOrder) {
      const double m = r.lo + (r.hi - r.lo) * double(c) / double(kCandidates - 1);
      const double zj = std::clamp(za + m * ds, z[j], z[j] + tolerance);
      const Reach next = reach_in_band(s, z, tolerance, j, zj);
      if (!have || next.last > best.last) {
        best = next;
        best_z = zj;
        have = true;
      }
      if (r.hi - r.lo <= 0) break;  // one slope: one candidate
    }
    out.push_back({j, best_z});
    a = j;
    za = best_z;
    r = best;
  }
  // The greedy fixes each vertex before it sees where the pinned end is: a
  // short last move often remains (a row's end on a slope). A vertex goes
  // where the move from the one before it to the one after stays in the band.
  std::vector<BandVertex> kept{out.front()};
  for (std::size_t m = 1; m + 1 < out.size(); ++m) {
    const BandVertex& p = kept.back();
    const BandVertex& q = out[m + 1];
    const double slope = (q.z - p.z) / (s[q.index] - s[p.index]);
    bool inside = true;
    for (std::size_t i = p.index + 1; i < q.index && inside; ++i) {
      const double f = p.z + slope * (s[i] - s[p.index]);
      inside = f >= z[i] - kEps && f <= z[i] + tolerance + kEps;
    }
    if (!inside) kept.push_back(out[m]);
  }
  kept.push_back(out.back());
  return kept;
}

}  // namespace cncstream::cam
