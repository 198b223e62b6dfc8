// The orthographic orbit camera (see camera.hpp).
#include "cncstream/viewer/camera.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace cncstream::viewer {

namespace {

constexpr double kDeg = std::numbers::pi / 180;
constexpr double kIsoElevation = 35.264389682754654;  // atan(1/sqrt(2)): the cube's diagonal
constexpr double kMinHalfHeight = 1e-4, kMaxHalfHeight = 1e6;

}  // namespace

Mat4 Mat4::identity() {
  Mat4 r;
  for (int k = 0; k < 4; ++k) r.at(k, k) = 1;
  return r;
}

std::array<float, 16> Mat4::to_floats() const {
  std::array<float, 16> f{};
  for (std::size_t k = 0; k < 16; ++k) f[k] = static_cast<float>(m[k]);
  return f;
}

Mat4 operator*(const Mat4& a, const Mat4& b) {
  Mat4 r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += a.at(i, k) * b.at(k, j);
      r.at(i, j) = s;
    }
  return r;
}

NamedView parse_named_view(const std::string& name) {
  if (name == "top") return NamedView::Top;
  if (name == "front") return NamedView::Front;
  if (name == "side") return NamedView::Side;
  if (name == "iso") return NamedView::Iso;
  std::string m = "unknown view '";
  m += name;
  m += "': use top, front, side or iso";
  throw std::invalid_argument(m);
}

void Camera::set_viewport(int width, int height) {
  if (width < 1 || height < 1) throw std::invalid_argument("viewer: the viewport must be at least 1 x 1 pixel");
  width_ = width;
  height_ = height;
}

void Camera::set_scene(const geometry::Box3& bounds) {
  if (bounds.empty()) {
    scene_center_ = {};
    scene_radius_ = 1;
    return;
  }
  scene_center_ = (bounds.lo + bounds.hi) * 0.5;
  scene_radius_ = std::max(norm(bounds.hi - bounds.lo) * 0.5, 1e-3);
}

void Camera::set_view(NamedView v) {
  switch (v) {
    case NamedView::Top: azimuth_deg_ = 0, elevation_deg_ = 90; break;
    case NamedView::Front: azimuth_deg_ = 0, elevation_deg_ = 0; break;
    case NamedView::Side: azimuth_deg_ = 90, elevation_deg_ = 0; break;
    case NamedView::Iso: azimuth_deg_ = 45, elevation_deg_ = kIsoElevation; break;
  }
}

geometry::Vec3 Camera::right() const {
  const double a = azimuth_deg_ * kDeg;
  return {std::cos(a), std::sin(a), 0};
}

geometry::Vec3 Camera::back() const {
  const double a = azimuth_deg_ * kDeg, e = elevation_deg_ * kDeg;
  return {std::cos(e) * std::sin(a), -std::cos(e) * std::cos(a), std::sin(e)};
}

geometry::Vec3 Camera::up() const { return cross(back(), right()); }

void Camera::fit(const geometry::Box3& bounds) {
  if (bounds.empty()) return;
  target_ = (bounds.lo + bounds.hi) * 0.5;
  const geometry::Vec3 r = right(), u = up();
  double ext_r = 0, ext_u = 0;
  for (int k = 0; k < 8; ++k) {
    const geometry::Vec3 c{k & 1 ? bounds.hi.x : bounds.lo.x, k & 2 ? bounds.hi.y : bounds.lo.y,
                 k & 4 ? bounds.hi.z : bounds.lo.z};
    ext_r = std::max(ext_r, std::fabs(dot(c - target_, r)));
    ext_u = std::max(ext_u, std::fabs(dot(c - target_, u)));
  }
  const double aspect = static_cast<double>(width_) / height_;
  half_height_ = std::clamp(std::max(ext_u, ext_r / aspect) * 1.08, kMinHalfHeight, kMaxHalfHeight);
}

void Camera::orbit(double dx_pixels, double dy_pixels) {
  azimuth_deg_ = std::fmod(azimuth_deg_ - 0.5 * dx_pixels, 360.0);
  elevation_deg_ = std::clamp(elevation_deg_ + 0.5 * dy_pixels, -90.0, 90.0);
}

void Camera::pan(double dx_pixels, double dy_pixels) {
  const double mpp = mm_per_pixel();
  target_ = target_ - right() * (dx_pixels * mpp) + up() * (dy_pixels * mpp);
}

void Camera::zoom_at(double factor, double x, double y) {
  if (!(factor > 0) || !std::isfinite(factor)) return;
  const double aspect = static_cast<double>(width_) / height_;
  const double nx = 2 * x / width_ - 1, ny = 1 - 2 * y / height_;
  const geometry::Vec3 r = right(), u = up();
  const geometry::Vec3 under = target_ + r * (nx * half_height_ * aspect) + u * (ny * half_height_);
  half_height_ = std::clamp(half_height_ / factor, kMinHalfHeight, kMaxHalfHeight);
  target_ = under - r * (nx * half_height_ * aspect) - u * (ny * half_height_);
}

double Camera::depth_half() const { return scene_radius_ + norm(target_ - scene_center_) + 1.0; }

Mat4 Camera::view_matrix() const {
  const geometry::Vec3 r = right(), u = up(), b = back();
  Mat4 v = Mat4::identity();
  const geometry::Vec3 rows[3] = {r, u, b};
  for (int i = 0; i < 3; ++i) {
    v.at(i, 0) = rows[i].x;
    v.at(i, 1) = rows[i].y;
    v.at(i, 2) = rows[i].z;
    v.at(i, 3) = -dot(rows[i], target_);
  }
  return v;
}

Mat4 Camera::projection_matrix() const {
  const double aspect = static_cast<double>(width_) / height_;
  Mat4 p = Mat4::identity();
  p.at(0, 0) = 1 / (half_height_ * aspect);
  p.at(1, 1) = 1 / half_height_;
  p.at(2, 2) = -1 / depth_half();  // view z toward the viewer: +D is the near plane
  return p;
}

WindowPoint Camera::project(const geometry::Vec3& world) const {
  const geometry::Vec3 d = world - target_;
  const double aspect = static_cast<double>(width_) / height_;
  const double nx = dot(d, right()) / (half_height_ * aspect), ny = dot(d, up()) / half_height_;
  const double nz = -dot(d, back()) / depth_half();
  return {(nx + 1) * 0.5 * width_, (1 - ny) * 0.5 * height_, (nz + 1) * 0.5};
}

bool Camera::may_see(const geometry::Box3& box) const {
  if (box.empty()) return false;
  double lo_x = HUGE_VAL, hi_x = -HUGE_VAL, lo_y = HUGE_VAL, hi_y = -HUGE_VAL;
  for (int k = 0; k < 8; ++k) {
    const WindowPoint p = project({k & 1 ? box.hi.x : box.lo.x, k & 2 ? box.hi.y : box.lo.y,
                                   k & 4 ? box.hi.z : box.lo.z});
    lo_x = std::min(lo_x, p.x), hi_x = std::max(hi_x, p.x), lo_y = std::min(lo_y, p.y), hi_y = std::max(hi_y, p.y);
  }
  return hi_x >= 0 && lo_x <= width_ && hi_y >= 0 && lo_y <= height_;
}

geometry::Vec3 Camera::unproject(const WindowPoint& p) const {
  const double aspect = static_cast<double>(width_) / height_;
  const double nx = 2 * p.x / width_ - 1, ny = 1 - 2 * p.y / height_, nz = 2 * p.depth - 1;
  return target_ + right() * (nx * half_height_ * aspect) + up() * (ny * half_height_) + back() * (-nz * depth_half());
}

}  // namespace cncstream::viewer
