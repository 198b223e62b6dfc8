// Part, cut and cutter surfaces for the viewer (see scene_mesh.hpp).
#include "cncstream/viewer/scene_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "cncstream/cam/stock.hpp"
#include "cncstream/image/deviation_map.hpp"

namespace cncstream::viewer {

namespace {

MeshVertex vertex(const geometry::Vec3& p, const geometry::Vec3& n, image::Rgb c) {
  return {static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z), static_cast<float>(n.x),
          static_cast<float>(n.y), static_cast<float>(n.z), c.r, c.g, c.b, 255};
}

}  // namespace

TriangleMesh part_surface(const geometry::Mesh& mesh, image::Rgb colour) {
  TriangleMesh out;
  out.vertices.reserve(mesh.size() * 3);
  out.indices.reserve(mesh.size() * 3);
  for (std::size_t t = 0; t < mesh.size(); ++t) {
    const geometry::Vec3 a = mesh.corner(t, 0), b = mesh.corner(t, 1), c = mesh.corner(t, 2);
    const geometry::Vec3 n = normalized(cross(b - a, c - a));
    for (const geometry::Vec3& p : {a, b, c}) {
      out.indices.push_back(static_cast<std::uint32_t>(out.vertices.size()));
      out.vertices.push_back(vertex(p, n, colour));
      out.bounds.add(p);
    }
  }
  return out;
}

double default_cutter_length(const cam::Cutter& cutter) { return std::max(6 * cutter.radius, 8.0); }

TriangleMesh cutter_surface(const cam::Cutter& cutter, const geometry::Vec3& tip, double length, int segments) {
  if (!(cutter.radius > 0)) throw std::invalid_argument("viewer: the cutter's radius must be positive");
  if (segments < 3) throw std::invalid_argument("viewer: a cutter needs at least 3 segments around");
  if (!(length > 0)) length = default_cutter_length(cutter);
  length = std::max(length, cutter.profile_top() + 1e-3);
  // The profile from the axis outward and up, (rho, z, normal's rho, normal's
  // z) per point; creases repeat a point with the other side's normal.
  struct P {
    double rho, z, nr, nz;
  };
  std::vector<P> prof;
  const double rc = cutter.core_radius(), rk = cutter.corner_radius, R = cutter.radius;
  if (cutter.is_apt()) {
    prof.push_back({0, 0, 0, -1});
    if (rc > 0) prof.push_back({rc, 0, 0, -1});
    if (rk > 0) {
      const int steps = 8;
      for (int k = 0; k <= steps; ++k) {
        const double phi = std::numbers::pi / 2 * k / steps;
        prof.push_back({rc + rk * std::sin(phi), rk * (1 - std::cos(phi)), std::sin(phi), -std::cos(phi)});
      }
    }
  } else {
    // V-bit, tapered ball: band by band (a cone piece is straight, an arc
    // is stepped by its tilt), a crease where the tilt jumps.
    const cam::CutterProfile bands = cutter.profile();
    for (std::size_t b = 0; b < bands.count; ++b) {
      const cam::ProfileBand& band = bands.band[b];
      const int steps = band.kind == cam::ProfileBand::Kind::Arc ? 8 : 1;
      for (int k = 0; k <= steps; ++k) {
        const double sn = band.sin0 + (band.sin1 - band.sin0) * k / steps;
        const double cs = std::sqrt(std::max(0.0, 1 - sn * sn));
        const double rho = band.kind == cam::ProfileBand::Kind::Arc ? band.a + band.r * sn
                                                               : band.rho0 + (band.rho1 - band.rho0) * k / steps;
        prof.push_back({rho, band.h(rho), sn, -cs});
      }
    }
  }
  prof.push_back({R, cutter.profile_top(), 1, 0});
  prof.push_back({R, length, 1, 0});
  prof.push_back({R, length, 0, 1});
  prof.push_back({0, length, 0, 1});

  TriangleMesh out;
  const auto ring = static_cast<std::uint32_t>(segments + 1);  // the seam repeats the first point
  for (const P& p : prof)
    for (int s = 0; s <= segments; ++s) {
      const double a = 2 * std::numbers::pi * s / segments, ca = std::cos(a), sa = std::sin(a);
      const geometry::Vec3 pos = tip + geometry::Vec3{p.rho * ca, p.rho * sa, p.z};
      out.vertices.push_back(vertex(pos, {p.nr * ca, p.nr * sa, p.nz}, kCutterColour));
      out.bounds.add(pos);
    }
  for (std::uint32_t k = 0; k + 1 < prof.size(); ++k) {
    const bool same_point = prof[k].rho == prof[k + 1].rho && prof[k].z == prof[k + 1].z;
    if (same_point) continue;  // a crease: no band between its two copies
    for (std::uint32_t s = 0; s < static_cast<std::uint32_t>(segments); ++s) {
      const std::uint32_t a = k * ring + s, b = a + 1, c = a + ring, d = c + 1;
      out.indices.insert(out.indices.end(), {a, b, d, a, d, c});
    }
  }
  return out;
}

namespace {

void check_height_field(const cam::GridSpec& grid, const std::vector<float>& heights) {
  if (grid.nx < 2 || grid.ny < 2) throw std::invalid_argument("viewer: a cut result needs at least 2 x 2 nodes");
  if (heights.size() != grid.size())
    throw std::invalid_argument(std::string("viewer: the cut result has ")
                                    .append(std::to_string(heights.size()))
                                    .append(" heights for a grid of ")
                                    .append(std::to_string(grid.size()))
                                    .append(" nodes"));
}

double highest(const std::vector<float>& heights) {
  double top = -std::numeric_limits<double>::infinity();
  for (const float v : heights)
    if (std::isfinite(v)) top = std::max(top, static_cast<double>(v));
  if (!std::isfinite(top)) throw std::invalid_argument("viewer: the cut result has no height anywhere");
  return top;
}

// A height field's top surface, each node coloured by colour_of(node index).
template <class ColourOf>
TriangleMesh height_field_surface(const cam::GridSpec& grid, const std::vector<float>& heights, double top,
                                  ColourOf colour_of) {
  TriangleMesh out;
  const std::size_t nx = grid.nx, ny = grid.ny;
  auto h = [&](std::size_t i, std::size_t j) { return static_cast<double>(heights[j * nx + i]); };
  out.vertices.reserve(grid.size());
  for (std::size_t j = 0; j < ny; ++j)
    for (std::size_t i = 0; i < nx; ++i) {
      const double zc = h(i, j);
      // The normal from the neighbours' slopes (one-sided at the border or
      // beside a node without a value).
      auto slope = [&](std::size_t a0, std::size_t b0, std::size_t a1, std::size_t b1, double step) {
        const double z0 = h(a0, b0), z1 = h(a1, b1);
        if (std::isfinite(z0) && std::isfinite(z1)) return (z1 - z0) / step;
        return 0.0;
      };
      const double sx = slope(i > 0 ? i - 1 : i, j, i + 1 < nx ? i + 1 : i, j,
                              grid.dx * static_cast<double>((i > 0) + (i + 1 < nx)));
      const double sy = slope(i, j > 0 ? j - 1 : j, i, j + 1 < ny ? j + 1 : j,
                              grid.dy * static_cast<double>((j > 0) + (j + 1 < ny)));
      const geometry::Vec3 p{grid.x(i), grid.y(j), std::isfinite(zc) ? zc : top};
      out.vertices.push_back(vertex(p, normalized(geometry::Vec3{-sx, -sy, 1}), colour_of(j * nx + i)));
      if (std::isfinite(zc)) out.bounds.add(p);
    }
  // Two triangles per cell; a triangle touching a node without a value is left out.
  for (std::size_t j = 0; j + 1 < ny; ++j)
    for (std::size_t i = 0; i + 1 < nx; ++i) {
      const auto a = static_cast<std::uint32_t>(j * nx + i), b = a + 1, c = a + static_cast<std::uint32_t>(nx),
                 d = c + 1;
      auto valid = [&](std::uint32_t v) { return std::isfinite(heights[v]); };
      if (valid(a) && valid(b) && valid(d)) out.indices.insert(out.indices.end(), {a, b, d});
      if (valid(a) && valid(d) && valid(c)) out.indices.insert(out.indices.end(), {a, d, c});
    }
  return out;
}

}  // namespace

CutSurface cut_surface(const cam::GridSpec& grid, const std::vector<float>& heights, const cam::DesignHeights& design,
                       double tolerance) {
  check_height_field(grid, heights);
  const double top = highest(heights);
  const cam::HeightFieldStock stock(grid, top, std::vector<double>(heights.begin(), heights.end()));
  const cam::DeviationResult dev = cam::compare_to_design(stock, design, tolerance);
  CutSurface out;
  out.stats = dev.stats;
  const image::DeviationScale scale{tolerance, dev.stats.has_gouge ? std::max(0.0, -dev.stats.largest_gouge.value) : 0.0,
                             std::max(0.0, dev.stats.largest_excess.value)};
  out.mesh = height_field_surface(grid, heights, top, [&](std::size_t k) {
    return dev.off_part[k] || !std::isfinite(dev.deviation[k]) ? image::DeviationPalette::off_part
                                                               : scale.colour(dev.deviation[k]);
  });
  return out;
}

CutSurface cut_surface(const cam::GridSpec& grid, const std::vector<float>& heights, const geometry::Mesh& design, double tolerance) {
  check_height_field(grid, heights);
  return cut_surface(grid, heights, cam::design_heights(design, grid), tolerance);
}

TriangleMesh stock_surface(const cam::GridSpec& grid, const std::vector<float>& heights, image::Rgb colour) {
  check_height_field(grid, heights);
  return height_field_surface(grid, heights, highest(heights), [&](std::size_t) { return colour; });
}

}  // namespace cncstream::viewer
