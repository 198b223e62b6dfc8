#include "cl_raster.hpp"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/enumerable_thread_specific.h>
#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <vector>

namespace cncstream::cam::cl_detail {

namespace {

constexpr std::size_t kTile = 128;  // nodes per tile side: 128 KB of doubles
// Culling hierarchy: blocks of 4 x 4 nodes inside super-blocks of 16 x 16.
constexpr std::size_t kBlock = 4;
constexpr std::size_t kSuper = 16;
constexpr std::size_t kBlocksPerSide = kTile / kBlock;
constexpr std::size_t kSupersPerSide = kTile / kSuper;
constexpr std::size_t kBlocksPerSuper = kSuper / kBlock;

struct Range {
  std::size_t lo = 0, hi = 0;  // [lo, hi)
  bool empty() const { return lo >= hi; }
};

// Nodes origin + k*step with coordinate in [a, b], widened by one node each
// side (the exact per-node tests decide), clipped to [0, n).
Range node_range(double a, double b, double origin, double step, std::size_t n) {
  double fa = std::ceil((a - origin) / step) - 1, fb = std::floor((b - origin) / step) + 1;
  if (!(fa <= fb) || n == 0) return {};
  const double top = static_cast<double>(n - 1);
  if (fb < 0 || fa > top) return {};
  fa = std::fmax(fa, 0.0);
  fb = std::fmin(fb, top);
  return {static_cast<std::size_t>(fa), static_cast<std::size_t>(fb) + 1};
}

Range intersect(Range a, std::size_t lo, std::size_t hi) { return {std::max(a.lo, lo), std::min(a.hi, hi)}; }

// Primitive ids per tile, compressed rows (counting sort: linear memory).
struct Bins {
  std::vector<std::uint32_t> offset;
  std::vector<std::uint32_t> items;
  const std::uint32_t* begin(std::size_t t) const { return items.data() + offset[t]; }
  const std::uint32_t* end(std::size_t t) const { return items.data() + offset[t + 1]; }
};

struct Layout {
  const GridSpec* spec;
  std::size_t j0, j1, tiles_x, tiles_y;
  std::size_t count() const { return tiles_x * tiles_y; }
};

// footprint(id) -> {x range, y range} of nodes the primitive may touch.
template <class Footprint>
Bins make_bins(const Layout& L, std::size_t n, Footprint footprint) {
  Bins b;
  b.offset.assign(L.count() + 1, 0);
  auto visit = [&](auto&& emit) {
    for (std::size_t id = 0; id < n; ++id) {
      Range rx, ry;
      if (!footprint(id, rx, ry)) continue;
      ry = intersect(ry, L.j0, L.j1);
      if (rx.empty() || ry.empty()) continue;
      const std::size_t tx0 = rx.lo / kTile, tx1 = (rx.hi - 1) / kTile;
      const std::size_t ty0 = (ry.lo - L.j0) / kTile, ty1 = (ry.hi - 1 - L.j0) / kTile;
      for (std::size_t ty = ty0; ty <= ty1; ++ty)
        for (std::size_t tx = tx0; tx <= tx1; ++tx) emit(ty * L.tiles_x + tx, static_cast<std::uint32_t>(id));
    }
  };
  visit([&](std::size_t tile, std::uint32_t) { ++b.offset[tile + 1]; });
  for (std::size_t t = 0; t < L.count(); ++t) b.offset[t + 1] += b.offset[t];
  b.items.resize(b.offset.back());
  std::vector<std::uint32_t> fill(b.offset.begin(), b.offset.end() - 1);
  visit([&](std::size_t tile, std::uint32_t id) { b.items[fill[tile]++] = id; });
  return b;
}

struct Context {
  const geometry::Mesh& mesh;
  const ClPrimitives& prims;
  const std::vector<FaceOffset>& offsets;
  const CutterShape& cutter;
  const GridSpec& spec;
  Layout layout;
  Bins faces, edges, vertices;
  double* out;
};

struct Scratch {
  std::vector<double> z = std::vector<double>(kTile * kTile);
  std::vector<double> block_min = std::vector<double>(kBlocksPerSide * kBlocksPerSide);
  std::vector<double> super_min = std::vector<double>(kSupersPerSide * kSupersPerSide);
};

void draw_faces(const Context& c, std::size_t tile, std::size_t i0, std::size_t i1, std::size_t jt0,
                std::size_t jt1, double* z, std::size_t w) {
  const GridSpec& g = c.spec;
  for (const std::uint32_t* p = c.faces.begin(tile); p != c.faces.end(tile); ++p) {
    const FaceOffset& f = c.offsets[*p];
    if (!f.active) continue;
    const Range ry = intersect(node_range(f.ymin(), f.ymax(), g.y0, g.dy, g.ny), jt0, jt1);
    for (std::size_t j = ry.lo; j < ry.hi; ++j) {
      const double y = g.y(j);
      // The row's x-interval inside the three sides (then the exact test).
      double xl = -HUGE_VAL, xr = HUGE_VAL;
      for (int k = 0; k < 3; ++k) {
        const double a = f.inx[k], b = (y - f.qy[k]) * f.iny[k] + f.tol;
        if (a > 0) xl = std::fmax(xl, f.qx[k] - b / a);
        else if (a < 0) xr = std::fmin(xr, f.qx[k] - b / a);
        else if (b < 0) xr = -HUGE_VAL;
      }
      if (!(xl <= xr)) continue;
      const Range rx = intersect(node_range(xl, xr, g.x0, g.dx, g.nx), i0, i1);
      double* row = z + (j - jt0) * w - i0;
      for (std::size_t i = rx.lo; i < rx.hi; ++i) {
        const double x = g.x(i);
        if (!f.contains(x, y)) continue;
        row[i] = std::max(row[i], f.value(x, y));
      }
    }
  }
}

void process_tile(const Context& c, std::size_t tile, Scratch& s) {
  const GridSpec& g = c.spec;
  const std::size_t tx = tile % c.layout.tiles_x, ty = tile / c.layout.tiles_x;
  const std::size_t i0 = tx * kTile, i1 = std::min(g.nx, i0 + kTile);
  const std::size_t jt0 = c.layout.j0 + ty * kTile, jt1 = std::min(c.layout.j1, jt0 + kTile);
  const std::size_t w = i1 - i0, h = jt1 - jt0;
  double* z = s.z.data();
  std::fill(z, z + w * h, kNoContact);

  draw_faces(c, tile, i0, i1, jt0, jt1, z, w);

  // Minimum of the buffer per block and per super-block: a primitive whose
  // best possible value over a (super-)block is not above it cannot change
  // any node there.
  const std::size_t bw = (w + kBlock - 1) / kBlock, bh = (h + kBlock - 1) / kBlock;
  auto block_nodes = [&](std::size_t bx, std::size_t by, std::size_t size) {
    return std::pair<Range, Range>{{i0 + bx * size, std::min(i1, i0 + (bx + 1) * size)},
                                   {jt0 + by * size, std::min(jt1, jt0 + (by + 1) * size)}};
  };
  auto refresh_block = [&](std::size_t bx, std::size_t by) {
    const auto [rx, ry] = block_nodes(bx, by, kBlock);
    double m = HUGE_VAL;
    for (std::size_t j = ry.lo; j < ry.hi; ++j)
      for (std::size_t i = rx.lo; i < rx.hi; ++i) m = std::min(m, z[(j - jt0) * w + (i - i0)]);
    s.block_min[by * kBlocksPerSide + bx] = m;
  };
  auto refresh_super = [&](std::size_t sx, std::size_t sy) {
    double m = HUGE_VAL;
    for (std::size_t by = sy * kBlocksPerSuper; by < std::min(bh, (sy + 1) * kBlocksPerSuper); ++by)
      for (std::size_t bx = sx * kBlocksPerSuper; bx < std::min(bw, (sx + 1) * kBlocksPerSuper); ++bx)
        m = std::min(m, s.block_min[by * kBlocksPerSide + bx]);
    s.super_min[sy * kSupersPerSide + sx] = m;
  };
  for (std::size_t by = 0; by < bh; ++by)
    for (std::size_t bx = 0; bx < bw; ++bx) refresh_block(bx, by);
  for (std::size_t sy = 0; sy * kSuper < h; ++sy)
    for (std::size_t sx = 0; sx * kSuper < w; ++sx) refresh_super(sx, sy);

  // Edges and vertices: visit the super-blocks and blocks of the footprint,
  // skip those the primitive cannot raise, then nodes where a cheap bound
  // shows it cannot (inside drop()).
  const double R = c.cutter.R;
  auto draw = [&](const Range& fx, const Range& fy, double zmax, auto&& distance_lb, auto&& drop) {
    const Range rx = intersect(fx, i0, i1), ry = intersect(fy, jt0, jt1);
    if (rx.empty() || ry.empty()) return;
    auto cannot_raise = [&](const Range& nx, const Range& ny, double floor_z, bool exact) {
      const double lb = distance_lb(g.x(nx.lo), g.y(ny.lo), g.x(nx.hi - 1), g.y(ny.hi - 1), exact);
      return lb > R || zmax - c.cutter.h(lb) <= floor_z;
    };
    for (std::size_t sy = (ry.lo - jt0) / kSuper; sy <= (ry.hi - 1 - jt0) / kSuper; ++sy) {
      for (std::size_t sx = (rx.lo - i0) / kSuper; sx <= (rx.hi - 1 - i0) / kSuper; ++sx) {
        auto [snx, sny] = block_nodes(sx, sy, kSuper);
        snx = intersect(snx, rx.lo, rx.hi);
        sny = intersect(sny, ry.lo, ry.hi);
        if (cannot_raise(snx, sny, s.super_min[sy * kSupersPerSide + sx], true)) continue;
        bool super_changed = false;
        for (std::size_t by = (sny.lo - jt0) / kBlock; by <= (sny.hi - 1 - jt0) / kBlock; ++by) {
          for (std::size_t bx = (snx.lo - i0) / kBlock; bx <= (snx.hi - 1 - i0) / kBlock; ++bx) {
            auto [nx, ny] = block_nodes(bx, by, kBlock);
            nx = intersect(nx, snx.lo, snx.hi);
            ny = intersect(ny, sny.lo, sny.hi);
            if (cannot_raise(nx, ny, s.block_min[by * kBlocksPerSide + bx], false)) continue;
            bool changed = false;
            for (std::size_t j = ny.lo; j < ny.hi; ++j) {
              const double y = g.y(j);
              double* row = z + (j - jt0) * w - i0;
              for (std::size_t i = nx.lo; i < nx.hi; ++i) {
                if (row[i] >= zmax) continue;
                const double v = drop(g.x(i), y, row[i]);
                if (v > row[i]) {
                  row[i] = v;
                  changed = true;
                }
              }
            }
            if (changed) {
              refresh_block(bx, by);
              super_changed = true;
            }
          }
        }
        if (super_changed) refresh_super(sx, sy);
      }
    }
  };

  for (const std::uint32_t* p = c.edges.begin(tile); p != c.edges.end(tile); ++p) {
    const auto& ab = c.prims.edges[*p];
    const geometry::Vec3 va = c.mesh.vertices[ab[0]], vb = c.mesh.vertices[ab[1]];
    const EdgeGeom e = make_edge(va, vb);
    const EdgeBand band = c.prims.edge_bands[*p];
    auto range_x = node_range(e.xmin - R, e.xmax + R, g.x0, g.dx, g.nx);
    auto range_y = node_range(e.ymin - R, e.ymax + R, g.y0, g.dy, g.ny);
    if (!band.trimmed() || e.L == 0) {
      draw(range_x, range_y, e.zmax,
           [&](double xa, double ya, double xb, double yb, bool exact) {
             return exact ? rect_segment_distance(e, xa, ya, xb, yb) : rect_segment_distance_lb(e, xa, ya, xb, yb);
           },
           [&](double x, double y, double current) { return edge_drop_above(e, c.cutter, x, y, current); });
      continue;
    }
    // A trimmed edge: inside its band the full edge contact, outside only its
    // end points (see EdgeBand). Blocks wholly outside the band are bounded by
    // their distance to the end points.
    auto side = [&](double x, double y) { return (x - e.ax) * e.uy - (y - e.ay) * e.ux; };
    auto point_rect = [](const geometry::Vec3& v, double xa, double ya, double xb, double yb) {
      const double dx = std::max(0.0, std::max(xa - v.x, v.x - xb)), dy = std::max(0.0, std::max(ya - v.y, v.y - yb));
      return std::sqrt(dx * dx + dy * dy);
    };
    draw(range_x, range_y, e.zmax,
         [&](double xa, double ya, double xb, double yb, bool exact) {
           const double d0 = side(xa, ya), d1 = side(xb, ya), d2 = side(xa, yb), d3 = side(xb, yb);
           const double dmin = std::min({d0, d1, d2, d3}), dmax = std::max({d0, d1, d2, d3});
           if (dmax < band.lo || dmin > band.hi)
             return std::min(point_rect(va, xa, ya, xb, yb), point_rect(vb, xa, ya, xb, yb));
           return exact ? rect_segment_distance(e, xa, ya, xb, yb) : rect_segment_distance_lb(e, xa, ya, xb, yb);
         },
         [&](double x, double y, double current) {
           const double d = side(x, y);
           if (d >= band.lo && d <= band.hi) return edge_drop_above(e, c.cutter, x, y, current);
           return std::max(vertex_drop_above(va, c.cutter, x, y, current), vertex_drop_above(vb, c.cutter, x, y, current));
         });
  }
  for (const std::uint32_t* p = c.vertices.begin(tile); p != c.vertices.end(tile); ++p) {
    const geometry::Vec3 v = c.mesh.vertices[c.prims.vertices[*p]];
    const EdgeGeom point = make_edge(v, v);
    draw(node_range(v.x - R, v.x + R, g.x0, g.dx, g.nx), node_range(v.y - R, v.y + R, g.y0, g.dy, g.ny), v.z,
         [&](double xa, double ya, double xb, double yb, bool exact) {
           return exact ? rect_segment_distance(point, xa, ya, xb, yb) : rect_segment_distance_lb(point, xa, ya, xb, yb);
         },
         [&](double x, double y, double current) { return vertex_drop_above(v, c.cutter, x, y, current); });
  }

  for (std::size_t j = jt0; j < jt1; ++j)
    std::copy(z + (j - jt0) * w, z + (j - jt0) * w + w, c.out + (j - c.layout.j0) * g.nx + i0);
}

}  // namespace

void rasterize_rows(const geometry::Mesh& mesh, const ClPrimitives& prims, const std::vector<FaceOffset>& faces,
                    const CutterShape& cutter, const GridSpec& spec,
                    std::size_t j0, std::size_t j1, double* z, const Checkpoint& checkpoint) {
  if (j1 <= j0 || spec.nx == 0) return;
  const Layout layout{&spec, j0, j1, (spec.nx + kTile - 1) / kTile, (j1 - j0 + kTile - 1) / kTile};
  const double R = cutter.R;
  Context c{mesh, prims, faces, cutter, spec, layout, {}, {}, {}, z};
  c.faces = make_bins(layout, prims.faces.size(), [&](std::size_t id, Range& rx, Range& ry) {
    const FaceOffset& f = faces[id];
    if (!f.active) return false;
    rx = node_range(f.xmin(), f.xmax(), spec.x0, spec.dx, spec.nx);
    ry = node_range(f.ymin(), f.ymax(), spec.y0, spec.dy, spec.ny);
    return true;
  });
  c.edges = make_bins(layout, prims.edges.size(), [&](std::size_t id, Range& rx, Range& ry) {
    const geometry::Vec3 a = mesh.vertices[prims.edges[id][0]], b = mesh.vertices[prims.edges[id][1]];
    rx = node_range(std::fmin(a.x, b.x) - R, std::fmax(a.x, b.x) + R, spec.x0, spec.dx, spec.nx);
    ry = node_range(std::fmin(a.y, b.y) - R, std::fmax(a.y, b.y) + R, spec.y0, spec.dy, spec.ny);
    return true;
  });
  c.vertices = make_bins(layout, prims.vertices.size(), [&](std::size_t id, Range& rx, Range& ry) {
    const geometry::Vec3 v = mesh.vertices[prims.vertices[id]];
    rx = node_range(v.x - R, v.x + R, spec.x0, spec.dx, spec.nx);
    ry = node_range(v.y - R, v.y + R, spec.y0, spec.dy, spec.ny);
    return true;
  });

  // Each tile writes only its own nodes, so the grid does not depend on which
  // thread ran which tile.
  const std::size_t tiles = layout.count();
  tbb::enumerable_thread_specific<Scratch> scratch;
  std::atomic<std::size_t> done{0};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tiles, 1), [&](const tbb::blocked_range<std::size_t>& r) {
    Scratch& s = scratch.local();
    for (std::size_t t = r.begin(); t != r.end(); ++t) {
      process_tile(c, t, s);
      if (checkpoint) checkpoint(double(++done) / double(tiles));
    }
  });
}

}  // namespace cncstream::cam::cl_detail
