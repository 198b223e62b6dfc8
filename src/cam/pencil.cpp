#include "cncstream/cam/pencil.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace cncstream::cam {

namespace {

// The crease test at one node along one axis: the slopes to either
// neighbour turn upward by at least tan(turn) (a valley, not a ridge).
bool valley(double before, double at, double after, double h, double min_turn) {
  const double into = (at - before) / h, out = (after - at) / h;
  return out - into >= min_turn && into <= 0 && out >= 0;
}

// Fewer points: from each kept point, the farthest later one that a
// straight move reaches staying on or above the CL, and within the
// tolerance of it, at every sample.
Polyline merged(const ClEngine& engine, const Polyline& p, const PencilOptions& o) {
  if (p.size() < 3) return p;
  constexpr std::size_t kWindow = 200;
  auto straight = [&](const geometry::Vec3& a, const geometry::Vec3& b) {
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    const auto n = std::max<std::size_t>(1, std::size_t(std::ceil(len / o.sample_step)));
    for (std::size_t s = 1; s < n; ++s) {
      const geometry::Vec3 q = a + (b - a) * (double(s) / double(n));
      const double cl = engine.height_at(q.x, q.y);
      if (cl > q.z + 1e-6 || q.z - cl > o.tolerance) return false;
    }
    return true;
  };
  Polyline out{p.front()};
  std::size_t i = 0;
  while (i + 1 < p.size()) {
    std::size_t j = i + 1;
    while (j + 1 < p.size() && j + 1 - i <= kWindow && straight(p[i], p[j + 1])) ++j;
    out.push_back(p[j]);
    i = j;
  }
  return out;
}

}  // namespace

std::vector<Polyline> pencil_passes(const ClEngine& engine, const XYBounds& b, const PencilOptions& o,
                                    const std::function<bool(double, double)>& wanted) {
  const GridSpec spec = GridSpec::covering(b.x0, b.y0, b.x1, b.y1, o.step, o.step);
  std::vector<Polyline> out;
  if (spec.nx < 3 || spec.ny < 3) return out;
  const ClGrid g = engine.compute(spec);
  const double turn = std::tan(o.min_turn_deg * std::numbers::pi / 180);
  const std::size_t nx = spec.nx, ny = spec.ny;
  std::vector<std::uint8_t> crease(spec.size(), 0);
  for (std::size_t j = 1; j + 1 < ny; ++j)
    for (std::size_t i = 1; i + 1 < nx; ++i) {
      const std::size_t k = j * nx + i;
      if (g.on_floor[k] || !wanted(spec.x(i), spec.y(j))) continue;
      const bool across_x = valley(g.at(i - 1, j), g.at(i, j), g.at(i + 1, j), spec.dx, turn);
      const bool across_y = valley(g.at(i, j - 1), g.at(i, j), g.at(i, j + 1), spec.dy, turn);
      crease[k] = across_x || across_y ? 1 : 0;
    }
  // Chains: from an unvisited crease node, on to an unvisited crease
  // neighbour (the straightest), both ways.
  std::vector<std::uint8_t> used(spec.size(), 0);
  auto next = [&](std::size_t k, long di_prev, long dj_prev, long& di_out, long& dj_out) -> long {
    const long i = long(k % nx), j = long(k / nx);
    long best = -1;
    double best_score = -HUGE_VAL;
    for (long dj = -1; dj <= 1; ++dj)
      for (long di = -1; di <= 1; ++di) {
        if (!di && !dj) continue;
        const long ii = i + di, jj = j + dj;
        if (ii < 0 || jj < 0 || ii >= long(nx) || jj >= long(ny)) continue;
        const std::size_t m = std::size_t(jj) * nx + std::size_t(ii);
        if (!crease[m] || used[m]) continue;
        const double score = double(di * di_prev + dj * dj_prev) / std::hypot(double(di), double(dj));
        if (score > best_score) {
          best_score = score;
          best = long(m);
          di_out = di;
          dj_out = dj;
        }
      }
    return best;
  };
  auto point = [&](std::size_t k) { return geometry::Vec3{spec.x(k % nx), spec.y(k / nx), 0}; };
  for (std::size_t start = 0; start < spec.size(); ++start) {
    if (!crease[start] || used[start]) continue;
    used[start] = 1;
    std::vector<std::size_t> fwd{start}, back;
    for (auto* chain : {&fwd, &back}) {
      long di = 0, dj = 0;
      std::size_t at = start;
      for (;;) {
        long ndi = 0, ndj = 0;
        const long m = next(at, di, dj, ndi, ndj);
        if (m < 0) break;
        used[std::size_t(m)] = 1;
        chain->push_back(std::size_t(m));
        at = std::size_t(m);
        di = ndi;
        dj = ndj;
      }
    }
    std::vector<std::size_t> nodes(back.rbegin(), back.rend());
    nodes.insert(nodes.end(), fwd.begin(), fwd.end());
    if (double(nodes.size() - 1) * o.step < o.min_length) continue;
    // Tip points on the exact CL (on the lattice), every move checked.
    auto on_cl = [&](geometry::Vec3 p) {
      if (o.lattice) {
        const double s = o.lattice->step;
        p.x = o.lattice->x0 + std::round((p.x - o.lattice->x0) / s) * s;
        p.y = o.lattice->y0 + std::round((p.y - o.lattice->y0) / s) * s;
      }
      p.z = engine.height_at(p.x, p.y);
      return p;
    };
    Polyline pl{on_cl(point(nodes.front()))};
    for (std::size_t n = 1; n < nodes.size(); ++n) {
      const geometry::Vec3 a = pl.back(), b = on_cl(point(nodes[n]));
      const double len = std::hypot(b.x - a.x, b.y - a.y);
      const auto steps = std::max<std::size_t>(1, std::size_t(std::ceil(len / o.sample_step)));
      // Samples on the CL; where one stands above the move between the
      // kept ones, the highest goes in and both halves are looked at again.
      std::vector<geometry::Vec3> q(steps + 1);
      q.front() = a;
      q.back() = b;
      for (std::size_t s = 1; s < steps; ++s)
        q[s] = on_cl({a.x + (b.x - a.x) * double(s) / double(steps), a.y + (b.y - a.y) * double(s) / double(steps), 0});
      std::vector<std::uint8_t> keep(q.size(), 0);
      std::vector<std::pair<std::size_t, std::size_t>> todo{{0, steps}};
      while (!todo.empty()) {
        const auto [lo, hi] = todo.back();
        todo.pop_back();
        const double span = std::hypot(q[hi].x - q[lo].x, q[hi].y - q[lo].y);
        std::size_t worst = 0;
        double above = 1e-6;
        for (std::size_t s = lo + 1; s < hi; ++s) {
          const double t = span > 0 ? std::hypot(q[s].x - q[lo].x, q[s].y - q[lo].y) / span : 0;
          const double over = q[s].z - (q[lo].z + (q[hi].z - q[lo].z) * t);
          if (over > above) {
            above = over;
            worst = s;
          }
        }
        if (worst == 0) continue;
        keep[worst] = 1;
        todo.push_back({lo, worst});
        todo.push_back({worst, hi});
      }
      for (std::size_t s = 1; s < steps; ++s)
        if (keep[s]) pl.push_back(q[s]);
      pl.push_back(b);
    }
    out.push_back(merged(engine, pl, o));
  }
  return out;
}

}  // namespace cncstream::cam
