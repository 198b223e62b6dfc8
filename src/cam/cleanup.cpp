#include "cncstream/cam/cleanup.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cncstream::cam {

namespace {

// The part of polyline `pl` whose along-coordinate lies in [a, b] (a < b),
// in the polyline's own order; end points interpolated on the chords.
Polyline clip_along(const Polyline& pl, double a, double b, bool along_x) {
  auto u = [&](const geometry::Vec3& p) { return along_x ? p.x : p.y; };
  Polyline out;
  for (std::size_t k = 0; k + 1 < pl.size(); ++k) {
    const geometry::Vec3 p = pl[k], q = pl[k + 1];
    const double up = u(p), uq = u(q);
    const double lo = std::min(up, uq), hi = std::max(up, uq);
    if (hi < a || lo > b) continue;
    auto at = [&](double uu) {
      if (uq == up) return p;
      const double t = std::clamp((uu - up) / (uq - up), 0.0, 1.0);
      return p + (q - p) * t;
    };
    const geometry::Vec3 s = (up >= a && up <= b) ? p : at(up < a ? a : b);
    const geometry::Vec3 e = (uq >= a && uq <= b) ? q : at(uq < a ? a : b);
    if (out.empty() || !(out.back().x == s.x && out.back().y == s.y && out.back().z == s.z)) out.push_back(s);
    out.push_back(e);
  }
  return out;
}

}  // namespace

std::vector<Polyline> cleanup_pieces(const RasterPath& path, const GridSpec& g, const std::vector<double>& residual,
                                     double tol, double reach, bool along_x) {
  if (residual.size() != g.size()) throw std::invalid_argument("cleanup_pieces: residual does not match the grid");
  const std::size_t ncol = along_x ? g.nx : g.ny, nacross = along_x ? g.ny : g.nx;
  const double c0 = along_x ? g.x0 : g.y0, dc = along_x ? g.dx : g.dy;
  const double a0 = along_x ? g.y0 : g.x0, da = along_x ? g.dy : g.dx;
  auto node = [&](std::size_t col, std::size_t j) { return along_x ? j * g.nx + col : col * g.nx + j; };
  const double half = 0.5 * path.stepover + 1e-9;
  const auto grow = static_cast<std::size_t>(std::ceil(reach / dc));
  std::vector<Polyline> out;
  for (const auto& row : path.rows) {
    if (row.size() < 2) continue;
    const double v = along_x ? row.front().y : row.front().x;
    const double jlo = std::ceil((v - half - a0) / da), jhi = std::floor((v + half - a0) / da);
    if (jhi < 0 || jlo > double(nacross - 1)) continue;
    const auto j0 = static_cast<std::size_t>(std::max(0.0, jlo));
    const auto j1 = static_cast<std::size_t>(std::min(double(nacross - 1), jhi));
    std::vector<std::uint8_t> need(ncol, 0);
    for (std::size_t c = 0; c < ncol; ++c)
      for (std::size_t j = j0; j <= j1 && !need[c]; ++j) {
        const double r = residual[node(c, j)];
        need[c] = std::isfinite(r) && r > tol;
      }
    // Grow along the row by the reach, then take the runs.
    std::vector<std::uint8_t> grown(ncol, 0);
    for (std::size_t c = 0; c < ncol; ++c)
      if (need[c])
        for (std::size_t k = c >= grow ? c - grow : 0; k <= std::min(ncol - 1, c + grow); ++k) grown[k] = 1;
    std::vector<std::pair<double, double>> runs;
    for (std::size_t c = 0; c < ncol;) {
      if (!grown[c]) {
        ++c;
        continue;
      }
      std::size_t e = c;
      while (e + 1 < ncol && grown[e + 1]) ++e;
      runs.push_back({c0 + double(c) * dc - 0.5 * dc, c0 + double(e) * dc + 0.5 * dc});
      c = e + 1;
    }
    const bool forward = (along_x ? row.back().x - row.front().x : row.back().y - row.front().y) >= 0;
    if (!forward) std::reverse(runs.begin(), runs.end());
    for (const auto& [a, b] : runs) {
      Polyline piece = clip_along(row, a, b, along_x);
      if (piece.size() >= 2) out.push_back(std::move(piece));
    }
  }
  return out;
}

}  // namespace cncstream::cam
