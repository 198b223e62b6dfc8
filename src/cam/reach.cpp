#include "cncstream/cam/reach.hpp"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <utility>

namespace cncstream::cam {

namespace {

// Pitch dividing `step` into whole parts when step >= pitch, else a whole
// multiple of step; nodes then fall on the lattice or on a few fractions.
double aligned_pitch(double step, double pitch) {
  if (!(step > 0)) return pitch;
  if (step >= pitch) return step / std::ceil(step / pitch - 1e-9);
  return step * std::max(1.0, std::floor(pitch / step + 1e-9));
}

struct Stamp {
  long di, dj;
  double h;  // profile height at that CL node
};

// CL nodes within R of a point whose lattice coordinates are (i + fx, j + fy),
// relative to (i, j), with the cutter's height there.
std::vector<Stamp> make_stamp(const Cutter& c, double dx, double dy, double fx, double fy) {
  std::vector<Stamp> s;
  const long ni = static_cast<long>(std::ceil(c.radius / dx)) + 1, nj = static_cast<long>(std::ceil(c.radius / dy)) + 1;
  const double r2 = c.radius * c.radius * (1 + 1e-12);
  for (long dj = -nj; dj <= nj; ++dj)
    for (long di = -ni; di <= ni; ++di) {
      const double ex = (double(di) - fx) * dx, ey = (double(dj) - fy) * dy;
      const double d2 = ex * ex + ey * ey;
      if (d2 <= r2) s.push_back({di, dj, c.profile_height(std::sqrt(d2))});
    }
  return s;
}

}  // namespace

GridSpec reach_lattice(const GridSpec& at, double x0, double y0, double x1, double y1, double pitch_x, double pitch_y) {
  if (!(pitch_x > 0) || !(pitch_y > 0)) throw std::invalid_argument("reach_lattice: pitch must be positive");
  const double dx = aligned_pitch(at.dx, pitch_x), dy = aligned_pitch(at.dy, pitch_y);
  // Origin: the first node of `at` moved back by whole cells to cover x0, y0.
  const double ox = at.x0 - std::ceil((at.x0 - x0) / dx - 1e-9) * dx;
  const double oy = at.y0 - std::ceil((at.y0 - y0) / dy - 1e-9) * dy;
  return GridSpec::covering(ox, oy, std::max(x1, ox), std::max(y1, oy), dx, dy);
}

std::vector<double> reach_heights(const ClGrid& cl, const Cutter& cutter, const GridSpec& at,
                                  const std::vector<std::uint8_t>& wanted, const Checkpoint& checkpoint) {
  if (wanted.size() != at.size()) throw std::invalid_argument("reach_heights: mask size differs from the grid");
  const GridSpec& g = cl.spec;
  std::vector<double> out(at.size(), std::numeric_limits<double>::quiet_NaN());
  if (g.nx == 0 || g.ny == 0) return out;

  // One stamp per distinct sub-cell offset of the wanted nodes (an aligned
  // lattice gives one or two per axis); past 64 of them, one per node.
  auto offset = [](double u, double o, double d, long& idx) {
    const double t = (u - o) / d;
    const double fl = std::floor(t + 1e-9);
    idx = static_cast<long>(fl);
    const double f = t - fl;
    return std::fabs(f) < 1e-9 ? 0.0 : f;
  };
  std::vector<long> col_i(at.nx), row_j(at.ny);
  std::vector<double> col_f(at.nx), row_f(at.ny);
  for (std::size_t i = 0; i < at.nx; ++i) col_f[i] = offset(at.x0 + double(i) * at.dx, g.x0, g.dx, col_i[i]);
  for (std::size_t j = 0; j < at.ny; ++j) row_f[j] = offset(at.y0 + double(j) * at.dy, g.y0, g.dy, row_j[j]);
  // Offsets within 1e-7 of a cell share a stamp key; the stamp itself uses
  // the first exact offset seen (the error is far below a micrometre).
  auto key = [](double f) { return static_cast<long long>(std::llround(f * 1e7)); };
  std::map<std::pair<long long, long long>, std::size_t> stamp_of;
  std::vector<std::vector<Stamp>> stamps;
  std::vector<std::size_t> which(at.size(), 0);
  const std::size_t max_stamps = 64;
  bool direct = false;
  for (std::size_t j = 0; j < at.ny && !direct; ++j)
    for (std::size_t i = 0; i < at.nx; ++i) {
      const std::size_t k = j * at.nx + i;
      if (!wanted[k]) continue;
      const auto kk = std::make_pair(key(col_f[i]), key(row_f[j]));
      auto it = stamp_of.find(kk);
      if (it == stamp_of.end()) {
        if (stamps.size() == max_stamps) { direct = true; break; }
        it = stamp_of.emplace(kk, stamps.size()).first;
        stamps.push_back(make_stamp(cutter, g.dx, g.dy, col_f[i], row_f[j]));
      }
      which[k] = it->second;
    }

  const double inf = std::numeric_limits<double>::infinity();
  auto at_node = [&](std::size_t i, std::size_t j, const std::vector<Stamp>& st) {
    double best = inf;
    const long ci = col_i[i], cj = row_j[j];
    for (const Stamp& s : st) {
      const long ii = ci + s.di, jj = cj + s.dj;
      if (ii < 0 || jj < 0 || ii >= long(g.nx) || jj >= long(g.ny)) continue;
      best = std::min(best, cl.z[std::size_t(jj) * g.nx + std::size_t(ii)] + s.h);
    }
    return best;
  };
  auto rows = [&](std::size_t j0, std::size_t j1) {
    for (std::size_t j = j0; j < j1; ++j)
      for (std::size_t i = 0; i < at.nx; ++i) {
        const std::size_t k = j * at.nx + i;
        if (!wanted[k]) continue;
        if (direct)
          out[k] = at_node(i, j, make_stamp(cutter, g.dx, g.dy, col_f[i], row_f[j]));
        else
          out[k] = at_node(i, j, stamps[which[k]]);
      }
  };
  // Bands of 16 rows as tasks: wanted nodes cluster (walls, pockets), so
  // small bands let idle threads take over a loaded region. Each node is
  // computed alone: the heights do not depend on the split.
  const std::size_t band = 16;
  const std::size_t bands = (at.ny + band - 1) / band;
  std::atomic<std::size_t> done{0};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, bands, 1), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t b = r.begin(); b != r.end(); ++b) {
      rows(b * band, std::min(at.ny, (b + 1) * band));
      if (checkpoint) checkpoint(double(++done) / double(bands));
    }
  });
  return out;
}

}  // namespace cncstream::cam
