// Separable exact squared Euclidean distance transform.
#include "cncstream/cam/distance_transform.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace cncstream::cam {

namespace {

// In place along one line: f[q] becomes min_p (f[p] + (step * (q - p))^2).
// With `pad`, the line is extended by one outside node (f = 0) at each end.
void lower_envelope(std::vector<double>& f, double step, bool pad, std::vector<double>& d, std::vector<long>& vtx,
                    std::vector<double>& zb) {
  const long off = pad ? 1 : 0;
  const long n = static_cast<long>(f.size()) + 2 * off;
  auto F = [&](long q) { return (q - off < 0 || q - off >= static_cast<long>(f.size())) ? 0.0 : f[static_cast<std::size_t>(q - off)]; };
  const double s2 = step * step;
  constexpr double inf = std::numeric_limits<double>::infinity();
  long first = 0;
  while (first < n && F(first) == inf) ++first;
  if (first == n) return;  // nothing outside on this line: all stay infinite
  vtx.assign(static_cast<std::size_t>(n), 0);
  zb.assign(static_cast<std::size_t>(n + 1), 0);
  d.assign(static_cast<std::size_t>(n), 0);
  long k = 0;
  vtx[0] = first;
  zb[0] = -inf;
  zb[1] = inf;
  for (long q = first + 1; q < n; ++q) {
    const double fq = F(q);
    if (fq == inf) continue;
    double s;
    for (;;) {
      const long p = vtx[static_cast<std::size_t>(k)];
      s = ((fq + s2 * static_cast<double>(q * q)) - (F(p) + s2 * static_cast<double>(p * p))) /
          (2 * s2 * static_cast<double>(q - p));
      if (s <= zb[static_cast<std::size_t>(k)] && k > 0) {
        --k;
        continue;
      }
      break;
    }
    ++k;
    vtx[static_cast<std::size_t>(k)] = q;
    zb[static_cast<std::size_t>(k)] = s;
    zb[static_cast<std::size_t>(k + 1)] = inf;
  }
  k = 0;
  for (long q = 0; q < n; ++q) {
    while (zb[static_cast<std::size_t>(k + 1)] < static_cast<double>(q)) ++k;
    const long p = vtx[static_cast<std::size_t>(k)];
    const double dq = static_cast<double>(q - p);
    d[static_cast<std::size_t>(q)] = s2 * dq * dq + F(p);
  }
  for (long q = off; q - off < static_cast<long>(f.size()); ++q) f[static_cast<std::size_t>(q - off)] = d[static_cast<std::size_t>(q)];
}

}  // namespace

std::vector<double> distance_to_outside(const GridSpec& g, const std::vector<std::uint8_t>& inside,
                                        bool beyond_is_outside) {
  if (inside.size() != g.size())
    throw std::invalid_argument("distance transform: " + std::to_string(inside.size()) + " flags for a grid of " +
                                std::to_string(g.size()) + " nodes");
  constexpr double inf = std::numeric_limits<double>::infinity();
  std::vector<double> f(g.size());
  for (std::size_t n = 0; n < f.size(); ++n) f[n] = inside[n] ? inf : 0.0;
  std::vector<double> line, d, zb;
  std::vector<long> vtx;
  // Columns (along y), then rows (along x).
  line.resize(g.ny);
  for (std::size_t i = 0; i < g.nx; ++i) {
    for (std::size_t j = 0; j < g.ny; ++j) line[j] = f[j * g.nx + i];
    lower_envelope(line, g.dy, beyond_is_outside, d, vtx, zb);
    for (std::size_t j = 0; j < g.ny; ++j) f[j * g.nx + i] = line[j];
  }
  line.resize(g.nx);
  for (std::size_t j = 0; j < g.ny; ++j) {
    for (std::size_t i = 0; i < g.nx; ++i) line[i] = f[j * g.nx + i];
    lower_envelope(line, g.dx, beyond_is_outside, d, vtx, zb);
    for (std::size_t i = 0; i < g.nx; ++i) f[j * g.nx + i] = std::sqrt(line[i]);
  }
  return f;
}

}  // namespace cncstream::cam
