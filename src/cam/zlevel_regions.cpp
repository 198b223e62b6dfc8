// The loops of one roughing level; see zlevel_regions.hpp.
#include "zlevel_regions.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "cncstream/cam/distance_transform.hpp"

namespace cncstream::cam::detail {

namespace {

double seg_dist(const geometry::Vec3& p, const geometry::Vec3& a, const geometry::Vec3& b) {
  const double ux = b.x - a.x, uy = b.y - a.y, l2 = ux * ux + uy * uy;
  double t = l2 > 0 ? ((p.x - a.x) * ux + (p.y - a.y) * uy) / l2 : 0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(p.x - a.x - t * ux, p.y - a.y - t * uy);
}

// Keeps pts[i0] and pts[i1] and what Douglas-Peucker keeps between them.
void dp(const Polyline& pts, std::size_t i0, std::size_t i1, double tol, std::vector<std::uint8_t>& keep) {
  std::vector<std::pair<std::size_t, std::size_t>> stack{{i0, i1}};
  while (!stack.empty()) {
    const auto [a, b] = stack.back();
    stack.pop_back();
    if (b <= a + 1) continue;
    double worst = -1;
    std::size_t at = a;
    for (std::size_t k = a + 1; k < b; ++k) {
      const double d = seg_dist(pts[k], pts[a], pts[b]);
      if (d > worst) worst = d, at = k;
    }
    if (worst > tol) {
      keep[at] = 1;
      stack.push_back({a, at});
      stack.push_back({at, b});
    }
  }
}

// 8-connected components of the inside nodes; labels from 1, 0 outside.
std::vector<std::uint32_t> label_components(const GridSpec& g, const std::vector<std::uint8_t>& in, std::size_t& count) {
  std::vector<std::uint32_t> label(g.size(), 0);
  std::vector<std::size_t> queue;
  count = 0;
  for (std::size_t s = 0; s < g.size(); ++s) {
    if (!in[s] || label[s]) continue;
    const auto id = static_cast<std::uint32_t>(++count);
    label[s] = id;
    queue.assign(1, s);
    while (!queue.empty()) {
      const std::size_t n = queue.back();
      queue.pop_back();
      const long i = static_cast<long>(n % g.nx), j = static_cast<long>(n / g.nx);
      for (long dj = -1; dj <= 1; ++dj)
        for (long di = -1; di <= 1; ++di) {
          const long ii = i + di, jj = j + dj;
          if (ii < 0 || jj < 0 || ii >= static_cast<long>(g.nx) || jj >= static_cast<long>(g.ny)) continue;
          const std::size_t m = static_cast<std::size_t>(jj) * g.nx + static_cast<std::size_t>(ii);
          if (in[m] && !label[m]) {
            label[m] = id;
            queue.push_back(m);
          }
        }
    }
  }
  return label;
}

// The component of the inside corner of the cell holding p (every corner of
// a cell is 8-adjacent to the others, so any inside one names it).
std::size_t component_at(const GridSpec& g, const std::vector<std::uint32_t>& label, const geometry::Vec3& p) {
  const double fi = std::floor((p.x - g.x0) / g.dx), fj = std::floor((p.y - g.y0) / g.dy);
  const long i = std::clamp(static_cast<long>(fi), 0L, static_cast<long>(g.nx) - 2);
  const long j = std::clamp(static_cast<long>(fj), 0L, static_cast<long>(g.ny) - 2);
  for (long dj = 0; dj <= 1; ++dj)
    for (long di = 0; di <= 1; ++di) {
      const std::size_t n = static_cast<std::size_t>(j + dj) * g.nx + static_cast<std::size_t>(i + di);
      if (label[n]) return label[n] - 1;
    }
  return 0;
}

}  // namespace

bool inside_loops(const geometry::Vec3& p, const std::vector<Polyline>& loops) {
  int winding = 0;
  for (const Polyline& l : loops)
    for (std::size_t k = 0; k < l.size(); ++k) {
      const geometry::Vec3& a = l[k];
      const geometry::Vec3& b = l[(k + 1) % l.size()];
      if (seg_dist(p, a, b) <= 1e-9) return true;
      const double side = (b.x - a.x) * (p.y - a.y) - (p.x - a.x) * (b.y - a.y);
      if (a.y <= p.y) {
        if (b.y > p.y && side > 0) ++winding;
      } else if (b.y <= p.y && side < 0) {
        --winding;
      }
    }
  return winding != 0;
}

std::size_t settle_boundary(LevelRegion& region, const std::vector<Polyline>* above) {
  std::vector<geometry::Vec3> out;
  if (above)
    for (const geometry::Vec3& c : region.corners)
      if (!inside_loops(c, *above)) out.push_back(c);
  std::size_t dropped = 0;
  for (RegionLoop& l : region.loops) {
    if (l.offset != 0) continue;
    const std::size_t before = l.points.size();
    if (!out.empty())
      std::erase_if(l.points, [&](const geometry::Vec3& v) {
        return std::any_of(out.begin(), out.end(), [&](const geometry::Vec3& c) { return c.x == v.x && c.y == v.y; });
      });
    dropped += before - l.points.size();
    // Then only exactly collinear points go (a corner lies on the lines of
    // its neighbouring chords, so they go with it only after this).
    l.points = simplify_closed(l.points, 1e-9);
    l.length = closed_length(l.points);
  }
  return dropped;
}

double closed_length(const Polyline& loop) {
  double l = 0;
  for (std::size_t k = 0; k < loop.size(); ++k) {
    const geometry::Vec3& a = loop[k];
    const geometry::Vec3& b = loop[(k + 1) % loop.size()];
    l += std::hypot(b.x - a.x, b.y - a.y);
  }
  return l;
}

Polyline simplify_closed(const Polyline& loop, double tol) {
  if (loop.size() < 4) return loop;
  // Split at the point farthest from the first; simplify both halves.
  std::size_t far = 0;
  double best = -1;
  for (std::size_t k = 1; k < loop.size(); ++k) {
    const double d = std::hypot(loop[k].x - loop[0].x, loop[k].y - loop[0].y);
    if (d > best) best = d, far = k;
  }
  Polyline closed = loop;
  closed.push_back(loop.front());
  std::vector<std::uint8_t> keep(closed.size(), 0);
  keep[0] = keep[far] = keep.back() = 1;
  dp(closed, 0, far, tol, keep);
  dp(closed, far, closed.size() - 1, tol, keep);
  Polyline out;
  for (std::size_t k = 0; k + 1 < closed.size(); ++k)
    if (keep[k]) out.push_back(closed[k]);
  return out;
}

LevelRegion level_region(const RegionInput& in) {
  const GridSpec& g = *in.grid;
  const std::vector<double>& phi = *in.phi;
  LevelRegion out;
  std::vector<std::uint8_t> inside(g.size());
  bool any = false;
  for (std::size_t n = 0; n < g.size(); ++n) any |= (inside[n] = phi[n] <= 0 ? 1 : 0) != 0;
  if (!any) {
    out.inside = std::move(inside);
    return out;
  }
  const std::vector<std::uint32_t> label = label_components(g, inside, out.components);

  auto add = [&](Polyline pts, int offset, double tol) {
    if (pts.size() < 2) return;
    if (tol > 0) pts = simplify_closed(pts, tol);
    RegionLoop l;
    l.component = component_at(g, label, pts.front());
    l.offset = offset;
    l.length = closed_length(pts);
    l.points = std::move(pts);
    out.loops.push_back(std::move(l));
  };

  ContourOptions co;
  co.xy_tolerance = in.boundary_tolerance;
  co.nested = true;
  LevelContours boundary = level_contours(g, phi, 0.0, *in.exact, co);
  out.queries += boundary.queries;
  out.corners = std::move(boundary.corner_points);
  // Not simplified here: see settle_boundary.
  for (auto& c : boundary.contours) add(std::move(c.points), 0, 0);

  // Inner loops: iso-lines of the distance to the boundary. A node's
  // distance to the nearest outside node overestimates its distance to the
  // boundary by up to a cell; half a cell is taken off.
  const double half = std::min(g.dx, g.dy) / 2;
  std::vector<double> depth = distance_to_outside(g, inside);
  double deepest = 0;
  for (std::size_t n = 0; n < g.size(); ++n) {
    depth[n] = inside[n] ? -(depth[n] - half) : half;  // negated: the region is {value <= -level}
    deepest = std::max(deepest, -depth[n]);
  }
  for (int k = 1; k * in.stepover <= deepest; ++k) {
    LevelContours ring = level_contours(g, depth, -k * in.stepover);
    for (auto& c : ring.contours) add(std::move(c.points), k, in.inner_tolerance);
  }
  out.inside = std::move(inside);
  return out;
}

}  // namespace cncstream::cam::detail
