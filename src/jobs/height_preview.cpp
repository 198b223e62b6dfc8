// Preview height images: a CL grid resampled, a program rasterised.
#include "cncstream/jobs/height_preview.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "cncstream/image/height_map.hpp"

namespace cncstream::jobs {

namespace {

constexpr float kNone = std::numeric_limits<float>::quiet_NaN();

// Nodes along an axis of length `extent`: as fine as `source_step` at most,
// max_side at most, both ends included.
std::size_t node_count(double extent, double source_step, std::size_t max_side) {
  if (!(extent > 0)) return 1;
  const double n = std::ceil(extent / source_step - 1e-9) + 1;
  return static_cast<std::size_t>(std::clamp(n, 2.0, static_cast<double>(std::max<std::size_t>(max_side, 2))));
}

// One axis: source values at p0 + k*d (n of them, read through `at`) onto
// m targets at t0 + i*h, each the highest source within half a target step,
// else the nearest source (upsampling, or past the source's last node).
template <class At, class Put>
void resample_max(std::size_t n, double p0, double d, std::size_t m, double t0, double h, At at, Put put) {
  const auto clampi = [&](double k) {
    return static_cast<std::size_t>(std::clamp(k, 0.0, static_cast<double>(n - 1)));
  };
  for (std::size_t i = 0; i < m; ++i) {
    const double x = t0 + static_cast<double>(i) * h;
    const double lo = std::ceil((x - h / 2 - p0) / d - 1e-9), hi = std::floor((x + h / 2 - p0) / d + 1e-9);
    float best;
    if (m == 1 || lo > hi || hi < 0 || lo > static_cast<double>(n - 1)) {
      best = at(clampi(std::round((x - p0) / d)));
    } else {
      best = -std::numeric_limits<float>::infinity();
      for (std::size_t k = clampi(lo), e = clampi(hi); k <= e; ++k) best = std::max(best, at(k));
    }
    put(i, best);
  }
}

}  // namespace

cam::XYBounds HeightPreview::bounds() const {
  return {grid.x0, grid.y0, grid.x0 + double(grid.nx ? grid.nx - 1 : 0) * grid.dx,
          grid.y0 + double(grid.ny ? grid.ny - 1 : 0) * grid.dy};
}

HeightPreview height_preview_from_grid(const cam::ClGrid& g, const cam::XYBounds& extent, const geometry::Vec3& offset,
                                       std::size_t max_side) {
  HeightPreview out;
  const cam::GridSpec& s = g.spec;
  if (s.size() == 0 || g.z.size() != s.size()) return out;
  const double ex = extent.x1 - extent.x0, ey = extent.y1 - extent.y0;
  const std::size_t nx = node_count(ex, s.dx, max_side), ny = node_count(ey, s.dy, max_side);
  const double hx = nx > 1 ? ex / double(nx - 1) : s.dx, hy = ny > 1 ? ey / double(ny - 1) : s.dy;
  // Separable: along x for every grid row, then along y for every column.
  std::vector<float> rows(nx * s.ny);
  for (std::size_t j = 0; j < s.ny; ++j)
    resample_max(
        s.nx, s.x0, s.dx, nx, extent.x0, hx, [&](std::size_t k) { return static_cast<float>(g.z[j * s.nx + k]); },
        [&](std::size_t i, float v) { rows[j * nx + i] = v; });
  out.z.assign(nx * ny, kNone);
  for (std::size_t i = 0; i < nx; ++i)
    resample_max(
        s.ny, s.y0, s.dy, ny, extent.y0, hy, [&](std::size_t k) { return rows[k * nx + i]; },
        [&](std::size_t j, float v) { out.z[j * nx + i] = v + static_cast<float>(offset.z); });
  out.grid = image::MapGrid{nx, ny, hx, hy, extent.x0 + offset.x, extent.y0 + offset.y};
  const auto [lo, hi] = std::minmax_element(g.z.begin(), g.z.end());
  out.z_min = *lo + offset.z;
  out.z_max = *hi + offset.z;
  return out;
}

HeightPreview height_preview_from_trace(const gcode::ProgramTrace& trace, std::size_t max_side) {
  HeightPreview out;
  double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL;
  for (const auto& s : trace.segments) {
    if (s.rapid) continue;
    for (const geometry::Vec3& p : {s.work_from(), s.work_to()}) {
      x0 = std::min(x0, p.x);
      y0 = std::min(y0, p.y);
      x1 = std::max(x1, p.x);
      y1 = std::max(y1, p.y);
    }
  }
  if (!(x1 >= x0)) return out;  // no cutting move
  const double ex = x1 - x0, ey = y1 - y0, longest = std::max(ex, ey);
  const std::size_t side = std::max<std::size_t>(max_side, 2);
  const double h = longest > 0 ? longest / double(side - 1) : 1;
  const std::size_t nx = node_count(ex, h, side), ny = node_count(ey, h, side);
  const double dx = nx > 1 ? ex / double(nx - 1) : h, dy = ny > 1 ? ey / double(ny - 1) : h;
  out.grid = image::MapGrid{nx, ny, dx, dy, x0, y0};
  out.z.assign(nx * ny, kNone);
  const auto node = [&](double x, double y) {
    const auto i = static_cast<std::size_t>(std::clamp(std::round((x - x0) / dx), 0.0, double(nx - 1)));
    const auto j = static_cast<std::size_t>(std::clamp(std::round((y - y0) / dy), 0.0, double(ny - 1)));
    return j * nx + i;
  };
  // Samples half a node apart along each move, so no node it crosses is skipped.
  const double ds = 0.5 * std::min(dx, dy);
  for (const auto& s : trace.segments) {
    if (s.rapid) continue;
    const geometry::Vec3 a = s.work_from(), b = s.work_to();
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    const auto n = static_cast<std::size_t>(std::max(1.0, std::ceil(len / ds)));
    for (std::size_t k = 0; k <= n; ++k) {
      const double f = double(k) / double(n);
      float& z = out.z[node(a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f)];
      const auto tip = static_cast<float>(a.z + (b.z - a.z) * f);
      if (!(z <= tip)) z = tip;  // NaN or higher: this pass cut deeper
    }
  }
  // Rows lie a stepover apart, often several nodes: grow each into the empty
  // nodes beside it (the mean of the known neighbours), a few nodes only, so
  // a sparse contour program is not smeared over its whole box.
  for (int pass = 0; pass < 16; ++pass) {
    const std::vector<float> prev = out.z;
    bool grew = false;
    for (std::size_t j = 0; j < ny; ++j)
      for (std::size_t i = 0; i < nx; ++i) {
        const std::size_t c = j * nx + i;
        if (!std::isnan(prev[c])) continue;
        double sum = 0;
        int cnt = 0;
        const auto take = [&](std::size_t k) {
          if (!std::isnan(prev[k])) {
            sum += prev[k];
            ++cnt;
          }
        };
        if (i > 0) take(c - 1);
        if (i + 1 < nx) take(c + 1);
        if (j > 0) take(c - nx);
        if (j + 1 < ny) take(c + nx);
        if (cnt) {
          out.z[c] = static_cast<float>(sum / cnt);
          grew = true;
        }
      }
    if (!grew) break;
  }
  out.z_min = HUGE_VAL;
  out.z_max = -HUGE_VAL;
  for (float z : out.z)
    if (!std::isnan(z)) {
      out.z_min = std::min(out.z_min, double(z));
      out.z_max = std::max(out.z_max, double(z));
    }
  return out;
}

image::RgbImage render_height_preview(const HeightPreview& h, int max_px, image::Rgb no_data) {
  if (h.empty()) throw std::invalid_argument("height preview: empty (no cutting move)");
  const cam::XYBounds b = h.bounds();
  const double ex = b.x1 - b.x0, ey = b.y1 - b.y0;
  image::HeightImageOptions o;
  o.width = o.height = max_px;
  if (ex > ey) o.height = std::max(1, static_cast<int>(std::lround(max_px * ey / ex)));
  else if (ey > ex) o.width = std::max(1, static_cast<int>(std::lround(max_px * ex / ey)));
  o.z_min = h.z_min;
  o.z_max = h.z_max;
  o.no_data = no_data;
  return image::render_height_image(h.grid, h.z, o);
}

}  // namespace cncstream::jobs
