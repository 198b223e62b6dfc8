#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "cncstream/cam/polyline_simplify.hpp"

using namespace cncstream;

namespace {
// Height of the chord polyline through the kept samples at sample k.
double chord_at(const std::vector<double>& s, const std::vector<double>& z, const std::vector<std::size_t>& kept,
                std::size_t k) {
  for (std::size_t m = 0; m + 1 < kept.size(); ++m) {
    const std::size_t a = kept[m], b = kept[m + 1];
    if (k >= a && k <= b) return z[a] + (z[b] - z[a]) * (s[k] - s[a]) / (s[b] - s[a]);
  }
  ADD_FAILURE() << "sample " << k << " not covered";
  return NAN;
}
}  // namespace

TEST(SimplifyProfile, CollinearCollapsesToEnds) {
  std::vector<double> s, z;
  for (int i = 0; i <= 100; ++i) {
    s.push_back(i * 0.1);
    z.push_back(2.0 - 0.3 * i * 0.1);
  }
  const auto kept = simplify_profile_above(s, z, 0.002);
  EXPECT_EQ(kept, (std::vector<std::size_t>{0, 100}));
}

TEST(SimplifyProfile, KeepsCornersAndNarrowPeaks) {
  // Flat, a one-sample spike, flat: the spike must survive any tolerance below its height.
  std::vector<double> s, z;
  for (int i = 0; i <= 50; ++i) {
    s.push_back(i);
    z.push_back(i == 25 ? 1.0 : 0.0);
  }
  const auto kept = simplify_profile_above(s, z, 0.5);
  EXPECT_NE(std::find(kept.begin(), kept.end(), 25u), kept.end());
  for (std::size_t k = 0; k < s.size(); ++k) EXPECT_GE(chord_at(s, z, kept, k), z[k] - 1e-9);
}

TEST(SimplifyProfile, NeverBelowAndWithinToleranceOnRandomProfiles) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> step(0.01, 0.2), dz(-0.05, 0.05);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<double> s{0}, z{0};
    double slope = 0;
    for (int i = 0; i < 400; ++i) {
      s.push_back(s.back() + step(rng));
      if (i % 37 == 0) slope = dz(rng) * 10;
      z.push_back(z.back() + slope * (s.back() - s[s.size() - 2]) + (i % 5 == 0 ? dz(rng) : 0.0));
    }
    const double tol = trial % 2 ? 0.002 : 0.05;
    const auto kept = simplify_profile_above(s, z, tol);
    ASSERT_EQ(kept.front(), 0u);
    ASSERT_EQ(kept.back(), s.size() - 1);
    for (std::size_t k = 0; k < s.size(); ++k) {
      const double c = chord_at(s, z, kept, k);
      EXPECT_GE(c, z[k] - 1e-8);
      EXPECT_LE(c, z[k] + tol + 1e-8);
    }
    EXPECT_LT(kept.size(), s.size());
  }
}
