#include "cncstream/gl/offset_tessellation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cncstream::gl {

namespace {

// The cutter's profile: the generalized APT one in closed form (flat, ball,
// bull-nose), any other (V-bit, tapered ball, grown ones) as its bands
// (cutter.hpp). rc: the flat core's radius (the tip's flat for a V-bit).
struct Profile {
  double R = 0, rk = 0, rc = 0;
  bool general = false;
  cam::CutterProfile bands;
  explicit Profile(const cam::Cutter& c)
      : R(c.radius),
        rk(c.type == cam::CutterType::Flat ? 0.0
           : c.type == cam::CutterType::Ball ? c.radius
                                         : std::clamp(c.corner_radius, 0.0, c.radius)),
        rc(R - rk),
        general(!c.is_apt()) {
    if (general) {
      bands = c.profile();
      R = bands.R;
      rk = 0;
      const cam::ProfileBand& b0 = bands.band[0];
      rc = b0.kind == cam::ProfileBand::Kind::Cone && b0.slope == 0 && b0.h0 == 0 ? b0.rho1 : 0.0;
    }
  }
  // Top of the inverted cutter at radius rho: -h(rho), concave, decreasing.
  double g(double rho) const {
    if (general) return -bands.h(rho);
    if (rho <= rc) return 0.0;
    const double u = std::min(rho - rc, rk);
    return -(rk - std::sqrt(std::max(0.0, (rk - u) * (rk + u))));
  }
};

// Largest vertical gap between the concave profile and its chord on [a, b]
// (the gap is concave in rho: ternary search).
double chord_gap(const Profile& p, double a, double b) {
  const double ga = p.g(a), gb = p.g(b);
  auto gap = [&](double r) { return p.g(r) - (ga + (gb - ga) * (r - a) / (b - a)); };
  double lo = a, hi = b;
  for (int it = 0; it < 100; ++it) {
    const double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
    if (gap(m1) < gap(m2)) lo = m1;
    else hi = m2;
  }
  return std::max(0.0, gap(0.5 * (lo + hi)));
}

void subdivide(const Profile& p, double a, double b, double tol, int depth, std::vector<double>& out) {
  if (depth < 40 && chord_gap(p, a, b) > tol) {
    const double m = 0.5 * (a + b);
    subdivide(p, a, m, tol, depth + 1, out);
    subdivide(p, m, b, tol, depth + 1, out);
    return;
  }
  out.push_back(b);
}

geometry::Vec3 face_normal(const geometry::Vec3& a, const geometry::Vec3& b, const geometry::Vec3& c) {
  geometry::Vec3 n = normalized(cross(b - a, c - a));
  if (n.z < 0) n = -n;
  return n;
}

}  // namespace

CutterCap::CutterCap(const cam::Cutter& cutter, double tolerance) {
  if (!(tolerance > 0) || !std::isfinite(tolerance))
    throw std::invalid_argument("GL CL engine: tessellation tolerance must be a positive number of mm");
  const Profile p(cutter);
  if (!(p.R > 0)) throw std::invalid_argument("GL CL engine: cutter radius must be positive");
  R_ = p.R;
  const double tol_r = tolerance / 2, tol_a = tolerance / 2;
  // Rings: the flat core's edge (exact, z = 0), then chords of the corner
  // arc (a general profile: of each band, so its kinks are rings).
  if (p.rc > 0) rho_.push_back(p.rc);
  if (p.general) {
    for (std::size_t k = 0; k < p.bands.count; ++k) {
      const cam::ProfileBand& b = p.bands.band[k];
      if (b.rho1 > p.rc) subdivide(p, std::max(b.rho0, p.rc), b.rho1, tol_r, 0, rho_);
    }
  } else if (p.rk > 0) {
    subdivide(p, p.rc, p.R, tol_r, 0, rho_);
  }
  double radial_gap = 0;
  for (std::size_t k = 0; k < rho_.size(); ++k) {
    const double a = k ? rho_[k - 1] : 0.0;
    if (rho_[k] > a) radial_gap = std::max(radial_gap, chord_gap(p, a, rho_[k]));
  }
  for (double r : rho_) z_.push_back(p.g(r));
  // Spokes: the angular chord of band k costs |slope_k| * rho_k * (1 - cos(pi/n));
  // the rim polygon misses a sliver R * (1 - cos(pi/n)) wide: at most a
  // twentieth of the tolerance (few nodes fall in it).
  double steep = 0;  // max over bands of |slope| * outer radius
  for (std::size_t k = 0; k < rho_.size(); ++k) {
    const double a = k ? rho_[k - 1] : 0.0, za = k ? z_[k - 1] : 0.0;
    if (rho_[k] > a) steep = std::max(steep, std::fabs((z_[k] - za) / (rho_[k] - a)) * rho_[k]);
  }
  auto spokes_for = [](double scale, double tol) -> double {  // n with scale * (1 - cos(pi/n)) <= tol
    if (scale <= tol) return 8;
    return std::ceil(M_PI / std::acos(1 - tol / scale));
  };
  // A multiple of 4: spokes along +-x and +-y (nodes straight beside a
  // vertex at exactly R, where the default grid bounds put rows, are on P's
  // rim; the engine's reach test leaves them to what lies below).
  const double n = 4 * std::ceil(std::max({8.0, spokes_for(steep, tol_a), spokes_for(p.R, tolerance / 20)}) / 4);
  if (n > 16384) throw std::invalid_argument("GL CL engine: tessellation tolerance too fine for this cutter (over 16384 spokes)");
  spokes_ = static_cast<std::size_t>(n);
  const double cos_half = std::cos(M_PI / n);
  height_error_bound_ = radial_gap + steep * (1 - cos_half);

  const std::size_t ns = spokes_, nr = rho_.size();
  points_.push_back({0, 0, 0});
  for (std::size_t k = 0; k < nr; ++k)
    for (std::size_t j = 0; j < ns; ++j) {
      const double th = 2 * M_PI * static_cast<double>(j) / n;
      points_.push_back({rho_[k] * std::cos(th), rho_[k] * std::sin(th), z_[k]});
    }
  auto pt = [&](std::size_t ring, std::size_t j) { return static_cast<std::uint32_t>(1 + ring * ns + j % ns); };
  // Cells: band 0 = the fan from the centre to ring 0; band b = ring b-1 to ring b.
  for (std::size_t b = 0; b < nr; ++b)
    for (std::size_t j = 0; j < ns; ++j) {
      if (b == 0) {
        triangles_.push_back({0, pt(0, j), pt(0, j + 1)});
        face_normal_.push_back(face_normal(points_[0], points_[pt(0, j)], points_[pt(0, j + 1)]));
      } else {
        triangles_.push_back({pt(b - 1, j), pt(b, j), pt(b, j + 1)});
        triangles_.push_back({pt(b - 1, j), pt(b, j + 1), pt(b - 1, j + 1)});
        face_normal_.push_back(face_normal(points_[pt(b - 1, j)], points_[pt(b, j)], points_[pt(b, j + 1)]));
      }
    }
  // The inverted cutter's side wall below the rim: one vertical face per rim
  // edge, facing out (for the flat cutter the top is a flat disc, so these
  // decide which rim edges sweep the top along a horizontal segment).
  const auto side0 = static_cast<std::uint32_t>(face_normal_.size());
  for (std::size_t j = 0; j < ns; ++j) {
    const double th = 2 * M_PI * (static_cast<double>(j) + 0.5) / n;
    face_normal_.push_back({std::cos(th), std::sin(th), 0});
  }
  auto cell = [&](std::size_t b, std::size_t j) { return static_cast<std::uint32_t>(b * ns + (j + ns) % ns); };
  for (std::size_t b = 0; b < nr; ++b)
    for (std::size_t j = 0; j < ns; ++j) {
      // The spoke edge of band b at angle j, between cells j-1 and j.
      edges_.push_back({b == 0 ? 0u : pt(b - 1, j), pt(b, j), cell(b, j + ns - 1), cell(b, j)});
      // Ring b's edge from spoke j to j+1: band b inside, band b+1 (or the bottom) outside.
      edges_.push_back({pt(b, j), pt(b, j + 1), cell(b, j), b + 1 < nr ? cell(b + 1, j) : static_cast<std::uint32_t>(side0 + j)});
    }
}

double CutterCap::sliver_width() const { return R_ * (1 - std::cos(M_PI / static_cast<double>(spokes_))); }

void CutterCap::silhouette_edges(const geometry::Vec3& d, std::vector<std::array<std::uint32_t, 2>>& out) const {
  out.clear();
  for (const CapEdge& e : edges_) {
    const double s1 = dot(face_normal_[e.f1], d), s2 = dot(face_normal_[e.f2], d);
    // Both faces parallel to d: the edge sweeps inside them, not needed.
    const bool both_parallel = std::fabs(s1) < 1e-12 && std::fabs(s2) < 1e-12;
    if (s1 * s2 <= 0 && !both_parallel) out.push_back({e.p, e.q});
  }
}

namespace {

// Where along the segment (u, from the node's foot) the cutter touches at
// lateral offset d: maximises g(u) = -m u - h(sqrt(d^2 + u^2)) over
// |u| <= sqrt(R^2 - d^2); g is concave. Returns u and g(u).
double best_u(const Profile& p, double m, double d, double& gbest) {
  const double w = std::sqrt(std::max(0.0, p.R * p.R - d * d));
  auto g = [&](double u) { return -m * u + p.g(std::sqrt(d * d + u * u)); };
  double u = 0;
  if (!p.general && p.rk == 0) {
    u = m > 0 ? -w : m < 0 ? w : 0.0;  // flat: the rim, uphill
  } else if (!p.general && p.rc == 0) {
    u = -m * w / std::sqrt(1 + m * m);  // ball: the great circle across the segment
  } else {
    double lo = -w, hi = w;
    for (int it = 0; it < 80; ++it) {
      const double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
      if (g(m1) < g(m2)) lo = m1;
      else hi = m2;
    }
    u = 0.5 * (lo + hi);
  }
  gbest = g(u);
  return u;
}

}  // namespace

void edge_generators(const cam::Cutter& cutter, const geometry::Vec3& a, const geometry::Vec3& b, double tolerance, std::vector<geometry::Vec3>& out) {
  out.clear();
  const Profile p(cutter);
  const double ex = b.x - a.x, ey = b.y - a.y, L = std::hypot(ex, ey);
  if (!(L > 1e-9 * (1 + std::fabs(b.z - a.z)))) return;
  const double ux = ex / L, uy = ey / L, nx = -uy, ny = ux;
  const double m = (b.z - a.z) / L;
  struct Sample {
    double d, F, u;
  };
  auto sample = [&](double d) {
    Sample s{d, 0, 0};
    s.u = best_u(p, m, d, s.F);
    return s;
  };
  // Chords of the concave F: the gap at an interval's middle is at least
  // half its largest gap, so a middle gap <= tolerance/2 bounds it.
  std::vector<Sample> done;
  std::vector<std::pair<Sample, Sample>> todo;
  const int n0 = 8;
  Sample prev = sample(-p.R);
  for (int k = 1; k <= n0; ++k) {
    const Sample next = sample(-p.R + 2 * p.R * k / n0);
    todo.push_back({prev, next});
    prev = next;
  }
  std::reverse(todo.begin(), todo.end());
  done.push_back(todo.back().first);
  while (!todo.empty()) {
    const auto [l, r] = todo.back();
    todo.pop_back();
    const Sample mid = sample(0.5 * (l.d + r.d));
    if (mid.F - 0.5 * (l.F + r.F) > tolerance / 2 && r.d - l.d > 1e-9 * p.R && done.size() < 65536) {
      todo.push_back({mid, r});
      todo.push_back({l, mid});
    } else {
      done.push_back(r);
    }
  }
  for (const Sample& s : done) out.push_back({s.u * ux + s.d * nx, s.u * uy + s.d * ny, s.F + m * s.u});
}

geometry::Vec3 upward_unit_normal(const geometry::Vec3& p0, const geometry::Vec3& p1, const geometry::Vec3& p2) {
  geometry::Vec3 n = normalized(cross(p1 - p0, p2 - p0));
  if (n.z < 0) n = -n;
  return n;
}

bool face_offset_triangle(const geometry::Vec3& p0, const geometry::Vec3& p1, const geometry::Vec3& p2, const cam::Cutter& cutter,
                          std::array<geometry::Vec3, 3>& out) {
  const Profile p(cutter);
  const geometry::Vec3 n = upward_unit_normal(p0, p1, p2);
  if (!(n.z >= 1e-8)) return false;
  const double nxy = std::hypot(n.x, n.y);
  geometry::Vec3 shift;
  if (p.general) {
    // The contact radius rho maximises t rho - h(rho) (t the plane's slope;
    // concave): the node sits rho downhill of the contact, h(rho) below it.
    double rho = 0;
    if (nxy >= 1e-9) {
      const double t = nxy / n.z;
      double lo = 0, hi = p.R;
      for (int it = 0; it < 200 && hi - lo > 1e-13 * p.R; ++it) {
        const double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
        if (t * m1 + p.g(m1) < t * m2 + p.g(m2)) lo = m1;
        else hi = m2;
      }
      rho = 0.5 * (lo + hi);
      shift = geometry::Vec3{n.x / nxy, n.y / nxy, 0} * rho;
    }
    shift.z = p.g(rho);
  } else {
    shift = n * p.rk - geometry::Vec3{0, 0, p.rk};
    if (nxy >= 1e-9) shift += geometry::Vec3{n.x / nxy, n.y / nxy, 0} * p.rc;
  }
  out = {p0 + shift, p1 + shift, p2 + shift};
  return true;
}

}  // namespace cncstream::gl
