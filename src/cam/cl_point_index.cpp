#include "cl_point_index.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>

namespace cncstream::cam::cl_detail {

namespace {

struct Box2 {
  double x0, y0, x1, y1;
};

}  // namespace

double PointIndex::top(std::uint32_t item) const {
  const std::uint32_t id = item & kIdMask;
  switch (item & ~kIdMask) {
    case kFace: {
      const auto& t = mesh_.triangles[prims_.faces[id]];
      const double z = std::max(mesh_.vertices[t[0]].z, std::max(mesh_.vertices[t[1]].z, mesh_.vertices[t[2]].z));
      return z + 1e-6;  // the inclusive test may evaluate the plane a hair outside
    }
    case kEdge: {
      const auto& e = prims_.edges[id];
      return std::max(mesh_.vertices[e[0]].z, mesh_.vertices[e[1]].z) + 1e-9 * (1 + std::fabs(mesh_.vertices[e[0]].z));
    }
    default:
      return mesh_.vertices[prims_.vertices[id]].z;
  }
}

double PointIndex::evaluate(std::uint32_t item, double x, double y, double best) const {
  const std::uint32_t id = item & kIdMask;
  switch (item & ~kIdMask) {
    case kFace: {
      const FaceOffset& f = faces_[id];
      return f.active && f.contains(x, y) ? f.value(x, y) : kNoContact;
    }
    case kEdge: return edge_drop_above(edges_[id], cutter_, x, y, best);
    default:
      return vertex_drop(mesh_.vertices[prims_.vertices[id]], cutter_, x, y);
  }
}

double PointIndex::box_bound(std::uint32_t item, double xa, double ya, double xb, double yb) const {
  const double reach = cutter_.R * (1 + 1e-12) + 1e-9;
  const std::uint32_t id = item & kIdMask;
  double z = 0, d = 0;
  switch (item & ~kIdMask) {
    case kFace: {
      // Linear over the box's part of the shifted triangle's box: the
      // largest value is at a corner of that part.
      const FaceOffset& f = faces_[id];
      if (!f.active) return kNoContact;
      const double ux0 = std::max(xa, f.xmin()), ux1 = std::min(xb, f.xmax());
      const double uy0 = std::max(ya, f.ymin()), uy1 = std::min(yb, f.ymax());
      if (ux0 > ux1 || uy0 > uy1) return kNoContact;
      const double v = std::max(std::max(f.value(ux0, uy0), f.value(ux1, uy0)),
                                 std::max(f.value(ux0, uy1), f.value(ux1, uy1)));
      // The margin covers a contained point a rounding outside the box.
      return std::min(top(item), v + 1e-9 * (1 + std::fabs(v) + std::fabs(f.gx) + std::fabs(f.gy)));
    }
    case kEdge:
      z = edges_[id].zmax;
      d = rect_segment_distance(edges_[id], xa, ya, xb, yb);
      break;
    default: {
      const geometry::Vec3 v = mesh_.vertices[prims_.vertices[id]];
      const double ddx = std::max(0.0, std::max(xa - v.x, v.x - xb)), ddy = std::max(0.0, std::max(ya - v.y, v.y - yb));
      z = v.z;
      d = std::sqrt(ddx * ddx + ddy * ddy);
    }
  }
  if (d > reach) return kNoContact;
  // h taken a nanometre nearer: the bound must not fall below a drop that
  // the exact evaluation, at a distance rounded a hair shorter, computes
  // higher (h is steep at the cutter's rim).
  return top(item) - cutter_.h(std::max(0.0, d * (1 - 1e-9) - 1e-9)) + 1e-9 * (1 + std::fabs(z));
}

PointIndex::PointIndex(const geometry::Mesh& mesh, const ClPrimitives& prims, const std::vector<FaceOffset>& faces,
                       const CutterShape& cutter)
    : mesh_(mesh), prims_(prims), cutter_(cutter), faces_(faces) {
  const double R = cutter.R;
  edges_.reserve(prims.edges.size());
  for (const auto& e : prims.edges) edges_.push_back(make_edge(mesh.vertices[e[0]], mesh.vertices[e[1]]));
  // Footprint of each item: the XY box outside which it cannot touch.
  auto footprint = [&](std::uint32_t item, Box2& b) {
    const std::uint32_t id = item & kIdMask;
    switch (item & ~kIdMask) {
      case kFace: {
        const FaceOffset& f = faces_[id];
        if (!f.active) return false;
        b = {f.xmin(), f.ymin(), f.xmax(), f.ymax()};
        break;
      }
      case kEdge: {
        const geometry::Vec3 p = mesh.vertices[prims.edges[id][0]], q = mesh.vertices[prims.edges[id][1]];
        b = {std::fmin(p.x, q.x) - R, std::fmin(p.y, q.y) - R, std::fmax(p.x, q.x) + R, std::fmax(p.y, q.y) + R};
        break;
      }
      default: {
        const geometry::Vec3 v = mesh.vertices[prims.vertices[id]];
        b = {v.x - R, v.y - R, v.x + R, v.y + R};
      }
    }
    const double margin = 1e-9 * (1 + std::fmax(std::fabs(b.x0), std::fabs(b.x1)) + std::fmax(std::fabs(b.y0), std::fabs(b.y1)));
    b.x0 -= margin;
    b.y0 -= margin;
    b.x1 += margin;
    b.y1 += margin;
    return true;
  };
  std::vector<std::uint32_t> all;
  all.reserve(prims.faces.size() + prims.edges.size() + prims.vertices.size());
  for (std::size_t k = 0; k < prims.faces.size(); ++k) all.push_back(kFace | static_cast<std::uint32_t>(k));
  for (std::size_t k = 0; k < prims.edges.size(); ++k) all.push_back(kEdge | static_cast<std::uint32_t>(k));
  for (std::size_t k = 0; k < prims.vertices.size(); ++k) all.push_back(kVertex | static_cast<std::uint32_t>(k));

  Box2 ext{HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  Box2 b{};
  for (auto item : all) {
    if (!footprint(item, b)) continue;
    ext = {std::fmin(ext.x0, b.x0), std::fmin(ext.y0, b.y0), std::fmax(ext.x1, b.x1), std::fmax(ext.y1, b.y1)};
  }
  if (!(ext.x0 <= ext.x1)) return;  // nothing to index
  x0_ = ext.x0;
  y0_ = ext.y0;
  const double w = ext.x1 - ext.x0, h = ext.y1 - ext.y0;
  const double n = static_cast<double>(all.size());
  // Cells about as small as the footprints allow, grown until the lists stay
  // linear in the number of primitives. Half the radius: a cell then lists
  // what lies within 2.5 radii of its centre rather than 3 (the plaque's
  // waterlines, 2.5 M queries: 1.65-1.9 s -> 1.4 s on two cores).
  // A V-bit's or tapered ball's cone rises steeply outside its tip, so an
  // item's bound falls off within a fraction of the reach: a quarter of the
  // radius and up to 64 entries an item make the bounds tight (the tapered
  // ball's plaque job: 48 -> 27 evaluations a query, 2.75 -> 2.51 s, the
  // index 22 MB larger). A ball's gentle rise leaves its bounds loose at any
  // cell size, and the larger index only costs (1.62 -> 1.74 s).
  const bool steep_profile = cutter.general;
  const double per_item = steep_profile ? 64 : 16;
  cell_ = std::fmax(std::fmax((steep_profile ? 0.25 : 0.5) * R, std::sqrt(w * h / n)), 1e-9 * (1 + w + h));
  auto cell_of = [&](double v, double origin, std::size_t cells) {
    const double k = std::floor((v - origin) / cell_);
    return static_cast<std::size_t>(std::clamp(k, 0.0, static_cast<double>(cells - 1)));
  };
  for (;;) {
    nx_ = static_cast<std::size_t>(std::floor(w / cell_)) + 1;
    ny_ = static_cast<std::size_t>(std::floor(h / cell_)) + 1;
    double entries = 0;
    if (static_cast<double>(nx_) * static_cast<double>(ny_) <= 4 * n + 1024) {
      for (auto item : all) {
        if (!footprint(item, b)) continue;
        entries += static_cast<double>(cell_of(b.x1, x0_, nx_) - cell_of(b.x0, x0_, nx_) + 1) *
                   static_cast<double>(cell_of(b.y1, y0_, ny_) - cell_of(b.y0, y0_, ny_) + 1);
      }
      // 16 entries an item (8 bytes each): a query near a wall evaluates
      // a fifth fewer items than at 8 (the plaque's waterlines).
      if (entries <= per_item * n + 4096) break;
    }
    cell_ *= 1.5;
  }
  // Each cell lists the items that can reach it, each with the highest drop
  // it can give anywhere in the cell (its top less the profile height at its
  // nearest distance to the cell), highest first: a query stops at the first
  // bound not above its best height, and skips what lies beyond the
  // cutter's reach of the cell. Sorting by the top alone made a query at the
  // foot of a wall evaluate the whole wall within the cell's reach (124
  // items a query on the plaque, 96 % of them giving nothing).
  auto cell_bound = [&](std::uint32_t item, std::size_t cx, std::size_t cy) {
    const double xa = x0_ + static_cast<double>(cx) * cell_, ya = y0_ + static_cast<double>(cy) * cell_;
    return box_bound(item, xa, ya, xa + cell_, ya + cell_);
  };
  // Two passes over the items in parallel (isolated: this runs inside the
  // engine's call_once, which a stolen task querying the same engine would
  // enter again): one counts each cell's entries, one places them; then
  // each cell's list is sorted by bound (and item), so the index does not
  // depend on the order the threads placed them in.
  auto visit = [&](auto&& emit) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, all.size(), 256), [&](const tbb::blocked_range<std::size_t>& r) {
      Box2 fb{};
      for (std::size_t k = r.begin(); k != r.end(); ++k) {
        const std::uint32_t item = all[k];
        if (!footprint(item, fb)) continue;
        const std::size_t cx0 = cell_of(fb.x0, x0_, nx_), cx1 = cell_of(fb.x1, x0_, nx_);
        const std::size_t cy0 = cell_of(fb.y0, y0_, ny_), cy1 = cell_of(fb.y1, y0_, ny_);
        for (std::size_t cy = cy0; cy <= cy1; ++cy)
          for (std::size_t cx = cx0; cx <= cx1; ++cx)
            if (const double bound = cell_bound(item, cx, cy); bound > kNoContact) emit(cy * nx_ + cx, item, bound);
      }
    });
  };
  tbb::this_task_arena::isolate([&] {
    std::vector<std::atomic<std::uint32_t>> count(nx_ * ny_);
    visit([&](std::size_t cell, std::uint32_t, double) { count[cell].fetch_add(1, std::memory_order_relaxed); });
    offset_.assign(nx_ * ny_ + 1, 0);
    for (std::size_t k = 0; k < count.size(); ++k) {
      offset_[k + 1] = offset_[k] + count[k].load(std::memory_order_relaxed);
      count[k].store(offset_[k], std::memory_order_relaxed);  // now the next free place
    }
    entries_.resize(offset_.back());
    visit([&](std::size_t cell, std::uint32_t item, double bound) {
      // Rounded up to a float: a smaller index, still an upper bound.
      float f = static_cast<float>(bound);
      if (static_cast<double>(f) < bound) f = std::nextafter(f, HUGE_VALF);
      entries_[count[cell].fetch_add(1, std::memory_order_relaxed)] = {item, f};
    });
    tbb::parallel_for(std::size_t{0}, offset_.size() - 1, [&](std::size_t k) {
      std::sort(entries_.begin() + offset_[k], entries_.begin() + offset_[k + 1], [](const Entry& p, const Entry& q) {
        return p.bound != q.bound ? p.bound > q.bound : p.item < q.item;
      });
    });
  });
}

std::size_t PointIndex::cell_at(double x, double y) const {
  const double kx = std::floor((x - x0_) / cell_), ky = std::floor((y - y0_) / cell_);
  if (!(kx >= 0 && ky >= 0 && kx < static_cast<double>(nx_) && ky < static_cast<double>(ny_))) return npos;
  return static_cast<std::size_t>(ky) * nx_ + static_cast<std::size_t>(kx);
}

std::size_t PointIndex::first_above(const SampledLine& line, std::size_t k0, std::size_t k1, double limit) const {
  if (entries_.empty()) return k1 + 1;
  for (std::size_t k = k0; k <= k1;) {
    // The run of points from k that share a cell, and their box.
    double xa = line.x(k), ya = line.y(k);
    const std::size_t cell = cell_at(xa, ya);
    double xb = xa, yb = ya;
    std::size_t last = k;
    while (last < k1) {
      const double x = line.x(last + 1), y = line.y(last + 1);
      if (cell_at(x, y) != cell) break;
      xa = std::min(xa, x), xb = std::max(xb, x), ya = std::min(ya, y), yb = std::max(yb, y);
      ++last;
    }
    if (cell != npos) {
      // drop() at each point is the cell's largest evaluation: an item above
      // the limit at some point is one whose bound over the run's box is.
      std::size_t first = last + 1;
      for (std::uint32_t e = offset_[cell]; e < offset_[cell + 1] && first > k; ++e) {
        const Entry en = entries_[e];
        if (en.bound <= limit) break;  // listed highest first
        if (box_bound(en.item, xa, ya, xb, yb) <= limit) continue;
        for (std::size_t m = k; m < first; ++m)
          if (evaluate(en.item, line.x(m), line.y(m), limit) > limit) {
            first = m;
            break;
          }
      }
      if (first <= last) return first;
    }
    k = last + 1;
  }
  return k1 + 1;
}

double PointIndex::drop(double x, double y) const {
  if (entries_.empty()) return kNoContact;
  const std::size_t cell = cell_at(x, y);
  if (cell == npos) return kNoContact;
  double best = kNoContact;
  for (std::uint32_t k = offset_[cell]; k < offset_[cell + 1]; ++k) {
    const Entry e = entries_[k];
    if (e.bound <= best) break;  // listed highest first: nothing below can win
    const double v = evaluate(e.item, x, y, best);
    if (v > best) best = v;
  }
  return best;
}

}  // namespace cncstream::cam::cl_detail
