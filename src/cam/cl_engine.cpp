#include "cncstream/cam/cl_engine.hpp"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <string>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include "cl_contact.hpp"
#include "cl_point_index.hpp"
#include "cl_primitives.hpp"
#include "cl_raster.hpp"
#include "cncstream/cam/thread_limit.hpp"

namespace cncstream::cam {

using cl_detail::kNoContact;

struct ClEngine::Impl {
  const geometry::Mesh* mesh;
  Cutter cutter;
  cl_detail::CutterShape shape;
  ClOptions options;
  double floor = 0;
  cl_detail::ClPrimitives prims;
  // The drawn facets' face offsets, prepared once: every grid and the point
  // index use them (the finishing's rows alone draw the part 47 times).
  std::vector<cl_detail::FaceOffset> faces;
  ClEngineStats stats;
  mutable std::once_flag index_once;
  mutable std::unique_ptr<cl_detail::PointIndex> index;

  Impl(const geometry::Mesh& m, const Cutter& c, ClOptions o) : mesh(&m), cutter(c), shape(c), options(o) {}

  void rows(const GridSpec& spec, std::size_t j0, std::size_t j1, double* z, std::uint8_t* on_floor,
            const Checkpoint& checkpoint) const {
    run_with_thread_limit(options.threads,
                          [&] { cl_detail::rasterize_rows(*mesh, prims, faces, shape, spec, j0, j1, z, checkpoint); });
    const std::size_t n = (j1 - j0) * spec.nx;
    for (std::size_t k = 0; k < n; ++k) {
      const bool untouched = z[k] == kNoContact;
      on_floor[k] = untouched ? 1 : 0;
      if (untouched || (options.floor_is_lowest && z[k] < floor)) z[k] = floor;
    }
  }
};

namespace {

void validate_cutter(const Cutter& c) {
  if (!(c.radius > 0) || !std::isfinite(c.radius))
    throw std::invalid_argument("CL engine: cutter radius must be positive and finite (got " + std::to_string(c.radius) + ")");
  if (c.type == CutterType::Bull && !(c.corner_radius >= 0 && c.corner_radius <= c.radius))
    throw std::invalid_argument("CL engine: bull-nose corner radius " + std::to_string(c.corner_radius) +
                                " must lie in [0, " + std::to_string(c.radius) + "]");
  if (!c.is_apt()) {
    try {
      (void)c.profile();
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("CL engine: cutter " + c.spec() + ": " + e.what());
    }
  }
}

void validate_mesh(const geometry::Mesh& m) {
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    const geometry::Vec3& p = m.vertices[v];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw std::invalid_argument("CL engine: mesh vertex " + std::to_string(v) + " has a non-finite coordinate");
  }
  if (m.triangles.size() >= (std::size_t{1} << 30))
    throw std::invalid_argument("CL engine: mesh has too many facets (" + std::to_string(m.triangles.size()) + ")");
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (auto idx : m.triangles[t])
      if (idx >= m.vertices.size())
        throw std::invalid_argument("CL engine: facet " + std::to_string(t) + " refers to vertex " + std::to_string(idx) +
                                    " but the mesh has " + std::to_string(m.vertices.size()) + " vertices");
}

void validate_spec(const GridSpec& s) {
  if (!(s.dx > 0) || !(s.dy > 0) || !std::isfinite(s.dx) || !std::isfinite(s.dy))
    throw std::invalid_argument("CL grid: steps must be positive and finite (dx " + std::to_string(s.dx) + ", dy " +
                                std::to_string(s.dy) + ")");
  if (!std::isfinite(s.x0) || !std::isfinite(s.y0)) throw std::invalid_argument("CL grid: origin must be finite");
  if (s.nx && s.ny && s.nx > (std::size_t{1} << 40) / s.ny)
    throw std::invalid_argument("CL grid: " + std::to_string(s.nx) + " x " + std::to_string(s.ny) + " nodes is too many");
}

}  // namespace

ClEngine::ClEngine(const geometry::Mesh& mesh, const Cutter& cutter, ClOptions options) {
  validate_cutter(cutter);
  validate_mesh(mesh);
  impl_ = std::make_unique<Impl>(mesh, cutter, options);
  Impl& d = *impl_;
  if (d.options.floor) {
    if (!std::isfinite(*d.options.floor)) throw std::invalid_argument("CL engine: floor must be finite");
    d.floor = *d.options.floor;
  } else {
    const geometry::Box3 b = mesh.bounds();
    d.floor = b.empty() ? 0.0 : b.lo.z;
  }
  d.prims = cl_detail::select_primitives(mesh, d.shape, d.options.skip_concave_edges);
  d.faces.resize(d.prims.faces.size());
  run_with_thread_limit(d.options.threads, [&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, d.faces.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t k = r.begin(); k != r.end(); ++k) {
        const auto& t = mesh.triangles[d.prims.faces[k]];
        d.faces[k] = cl_detail::face_offset(mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]], d.shape);
      }
    });
  });
  d.stats.facets = mesh.triangles.size();
  d.stats.face_offsets = d.prims.faces.size();
  d.stats.edges = d.prims.edges_total;
  d.stats.edges_drawn = d.prims.edges.size();
  d.stats.vertices = d.prims.vertices_total;
  d.stats.vertices_drawn = d.prims.vertices.size();
}

ClEngine::~ClEngine() = default;
ClEngine::ClEngine(ClEngine&&) noexcept = default;
ClEngine& ClEngine::operator=(ClEngine&&) noexcept = default;

const Cutter& ClEngine::cutter() const { return impl_->cutter; }
double ClEngine::floor() const { return impl_->floor; }
const ClEngineStats& ClEngine::stats() const { return impl_->stats; }

ClGrid ClEngine::compute(const GridSpec& spec, const Checkpoint& checkpoint) const {
  validate_spec(spec);
  ClGrid g;
  g.spec = spec;
  g.floor = impl_->floor;
  g.z.resize(spec.size());
  g.on_floor.resize(spec.size());
  if (spec.size()) impl_->rows(spec, 0, spec.ny, g.z.data(), g.on_floor.data(), checkpoint);
  return g;
}

void ClEngine::compute_tiles(const GridSpec& spec, const std::function<void(const ClTile&)>& sink,
                             const Checkpoint& checkpoint) const {
  validate_spec(spec);
  if (!spec.size()) return;
  const std::size_t row_bytes = spec.nx * (sizeof(double) + sizeof(std::uint8_t));
  const std::size_t rows = std::clamp<std::size_t>(impl_->options.max_tile_bytes / row_bytes, 1, spec.ny);
  ClTile tile;
  tile.grid.floor = impl_->floor;
  for (std::size_t j0 = 0; j0 < spec.ny; j0 += rows) {
    const std::size_t j1 = std::min(spec.ny, j0 + rows);
    tile.j0 = j0;
    tile.grid.spec = spec;
    tile.grid.spec.y0 = spec.y(j0);
    tile.grid.spec.ny = j1 - j0;
    tile.grid.z.resize(tile.grid.spec.size());
    tile.grid.on_floor.resize(tile.grid.spec.size());
    Checkpoint within;
    if (checkpoint)
      within = [&checkpoint, j0, j1, ny = spec.ny](double f) { checkpoint((double(j0) + f * double(j1 - j0)) / double(ny)); };
    impl_->rows(spec, j0, j1, tile.grid.z.data(), tile.grid.on_floor.data(), within);
    sink(tile);
  }
}

double ClEngine::height_at(double x, double y, bool& on_floor) const {
  const Impl& d = *impl_;
  std::call_once(d.index_once, [&] { d.index = std::make_unique<cl_detail::PointIndex>(*d.mesh, d.prims, d.faces, d.shape); });
  const double z = d.index->drop(x, y);
  on_floor = z == kNoContact;
  return on_floor || (d.options.floor_is_lowest && z < d.floor) ? d.floor : z;
}

std::size_t ClEngine::first_above(const SampledLine& line, std::size_t k0, std::size_t k1, double limit) const {
  const Impl& d = *impl_;
  if (!(d.floor <= limit)) {
    // Where nothing is touched the floor itself is above the limit: point by point.
    for (std::size_t k = k0; k <= k1; ++k)
      if (height_at(line.x(k), line.y(k)) > limit) return k;
    return k1 + 1;
  }
  std::call_once(d.index_once, [&] { d.index = std::make_unique<cl_detail::PointIndex>(*d.mesh, d.prims, d.faces, d.shape); });
  // At or below the limit, the floor never decides: a height is above it
  // exactly when a primitive's drop is.
  return d.index->first_above(line, k0, k1, limit);
}

double ClEngine::height_at(double x, double y) const {
  bool on_floor = false;
  return height_at(x, y, on_floor);
}

}  // namespace cncstream::cam
