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
// 401 samples at random spacing: slopes that change every 37 samples and
// steps every fifth.
void random_profile(std::mt19937& rng, std::vector<double>& s, std::vector<double>& z) {
  std::uniform_real_distribution<double> step(0.01, 0.2), dz(-0.05, 0.05);
  s = {0};
  z = {0};
  double slope = 0;
  for (int i = 0; i < 400; ++i) {
    s.push_back(s.back() + step(rng));
    if (i % 37 == 0) slope = dz(rng) * 10;
    z.push_back(z.back() + slope * (s.back() - s[s.size() - 2]) + (i % 5 == 0 ? dz(rng) : 0.0));
  }
}
}  // namespace

TEST(SimplifyProfile, CollinearCollapsesToEnds) {
  std::vector<double> s, z;
  for (int i = 0; i <= 100; ++i) {
    s.push_back(i * 0.1);
    z.push_back(2.0 - 0.3 * i * 0.1);
  }
  const auto kept = cam::simplify_profile_above(s, z, 0.002);
  EXPECT_EQ(kept, (std::vector<std::size_t>{0, 100}));
}

TEST(SimplifyProfile, KeepsCornersAndNarrowPeaks) {
  // Flat, a one-sample spike, flat: the spike must survive any tolerance below its height.
  std::vector<double> s, z;
  for (int i = 0; i <= 50; ++i) {
    s.push_back(i);
    z.push_back(i == 25 ? 1.0 : 0.0);
  }
  const auto kept = cam::simplify_profile_above(s, z, 0.5);
  EXPECT_NE(std::find(kept.begin(), kept.end(), 25u), kept.end());
  for (std::size_t k = 0; k < s.size(); ++k) EXPECT_GE(chord_at(s, z, kept, k), z[k] - 1e-9);
}

TEST(SimplifyProfile, NeverBelowAndWithinToleranceOnRandomProfiles) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<double> s, z;
    random_profile(rng, s, z);
    const double tol = trial % 2 ? 0.002 : 0.05;
    const auto kept = cam::simplify_profile_above(s, z, tol);
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

namespace {
// Height of the band-fitted polyline at s (between its vertices).
double band_at(const std::vector<double>& s, const std::vector<cam::BandVertex>& v, double at) {
  for (std::size_t m = 0; m + 1 < v.size(); ++m) {
    const double sa = s[v[m].index], sb = s[v[m + 1].index];
    if (at >= sa - 1e-12 && at <= sb + 1e-12) return v[m].z + (v[m + 1].z - v[m].z) * (at - sa) / (sb - sa);
  }
  ADD_FAILURE() << "s = " << at << " not covered";
  return NAN;
}

void expect_in_band(const std::vector<double>& s, const std::vector<double>& z, const std::vector<cam::BandVertex>& v,
                    double tol) {
  ASSERT_GE(v.size(), 2u);
  EXPECT_EQ(v.front().index, 0u);
  EXPECT_EQ(v.back().index, s.size() - 1);
  EXPECT_EQ(v.front().z, z.front());
  EXPECT_EQ(v.back().z, z.back());
  for (std::size_t k = 0; k < s.size(); ++k) {
    const double f = band_at(s, v, s[k]);
    ASSERT_GE(f, z[k] - 1e-9) << "below the profile at sample " << k;
    ASSERT_LE(f, z[k] + tol + 1e-9) << "above the band at sample " << k;
  }
}
}  // namespace

TEST(FitProfileInBand, ConvexArcGivesMovesOfSqrt8RT) {
  // A ball of radius R rolling over a sharp edge: its CL is a circle of
  // radius R. A circumscribed polyline within T takes moves of sqrt(8 R T)
  // (a chord whose sag is T, tangent in its middle); samples on the circle
  // alone (simplify_profile_above) cannot merge at all. The band is
  // vertical: on a slope of angle a it is T cos a wide across the path, so
  // the moves shorten as sqrt(cos a); the top of the circle (|a| < 30 deg)
  // is where sqrt(8 R T) holds.
  for (const double r : {1.5875, 3.0}) {
    for (const double tol : {0.002, 0.01}) {
      std::vector<double> s, z;
      for (double x = -0.5 * r; x <= 0.5 * r; x += 0.001) {
        s.push_back(x);
        z.push_back(std::sqrt(r * r - x * x));
      }
      const auto v = cam::fit_profile_in_band(s, z, tol);
      expect_in_band(s, z, v, tol);
      std::vector<double> lengths;
      // Inner moves only: the pinned ends start on the circle, not T above it.
      for (std::size_t m = 1; m + 2 < v.size(); ++m) {
        const double ds = s[v[m + 1].index] - s[v[m].index];
        lengths.push_back(std::hypot(ds, v[m + 1].z - v[m].z));
      }
      ASSERT_GE(lengths.size(), 4u);
      std::sort(lengths.begin(), lengths.end());
      const double expected = std::sqrt(8 * r * tol);
      const double median = lengths[lengths.size() / 2];
      EXPECT_NEAR(median, expected, 0.1 * expected) << "R " << r << " T " << tol;
      EXPECT_GT(lengths.front(), 0.8 * expected) << "R " << r << " T " << tol;
      EXPECT_GT(cam::simplify_profile_above(s, z, tol).size(), 10 * v.size());
    }
  }
}

TEST(FitProfileInBand, VCreaseKeepsItsVertex) {
  // A V-groove's crease (the CL bends up sharply on both sides): the path
  // must go down into it, to within the tolerance of its bottom.
  std::vector<double> s, z;
  for (int i = -500; i <= 500; ++i) {
    s.push_back(i * 0.01);
    z.push_back(std::fabs(i * 0.01) * 0.8 - 2.0);
  }
  const double tol = 0.01;
  const auto v = cam::fit_profile_in_band(s, z, tol);
  expect_in_band(s, z, v, tol);
  EXPECT_LE(band_at(s, v, 0.0), -2.0 + tol + 1e-9);
  EXPECT_LE(v.size(), 4u);  // straight flanks: one move down, one up
  bool near_crease = false;
  for (const cam::BandVertex& b : v) near_crease = near_crease || std::fabs(s[b.index]) <= tol / 0.8 + 1e-9;
  EXPECT_TRUE(near_crease);
}

TEST(FitProfileInBand, RidgeIsPassedAboveWithinTheBand) {
  // A sharp ridge (Lambda): nothing may cut its top, and nothing passes
  // higher than the tolerance above it.
  std::vector<double> s, z;
  for (int i = -300; i <= 300; ++i) {
    s.push_back(i * 0.01);
    z.push_back(-std::fabs(i * 0.01) * 1.5);
  }
  const auto v = cam::fit_profile_in_band(s, z, 0.005);
  expect_in_band(s, z, v, 0.005);
  EXPECT_GE(band_at(s, v, 0.0), 0.0 - 1e-9);
}

TEST(FitProfileInBand, InBandAndNoMoreVerticesThanSimplifyOnRandomProfiles) {
  std::mt19937 rng(11);
  std::size_t fitted = 0, kept = 0;
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<double> s, z;
    random_profile(rng, s, z);
    const double tol = trial % 2 ? 0.002 : 0.05;
    const auto v = cam::fit_profile_in_band(s, z, tol);
    expect_in_band(s, z, v, tol);
    fitted += v.size();
    kept += cam::simplify_profile_above(s, z, tol).size();
  }
  EXPECT_LT(fitted, kept);
}

TEST(FitProfileInBand, ZeroToleranceMergesOnlyCollinearSamples) {
  std::vector<double> s{0, 1, 2, 3, 4}, z{0, 1, 2, 2, 2};
  const auto v = cam::fit_profile_in_band(s, z, 0);
  ASSERT_EQ(v.size(), 3u);
  EXPECT_EQ(v[1].index, 2u);
  EXPECT_EQ(v[1].z, 2.0);
}
