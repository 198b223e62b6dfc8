#pragma once
// The viewer's camera, pure math (no GL): an orthographic view of a target
// point from an azimuth and an elevation, +Z up. Orthographic because a
// machinist reads a part's top, front and side views at true scale, and
// zooming toward the cursor then keeps the point under it exactly in place.
//
// Azimuth 0 looks from -Y toward +Y (the front view), 90 degrees from +X
// (the right side); elevation 90 degrees looks straight down with +Y up on
// the screen. Window pixels: x to the right, y down, (0, 0) the top-left
// corner; depth 0 at the near plane and 1 at the far one (GL's window depth).
#include <array>
#include <cstddef>
#include <string>

#include "cncstream/geometry/vec3.hpp"

namespace cncstream::viewer {

// Column-major 4x4 (OpenGL's layout), in doubles; to_floats() for uniforms.
struct Mat4 {
  std::array<double, 16> m{};
  static Mat4 identity();
  double at(int row, int col) const { return m[static_cast<std::size_t>(col) * 4 + static_cast<std::size_t>(row)]; }
  double& at(int row, int col) { return m[static_cast<std::size_t>(col) * 4 + static_cast<std::size_t>(row)]; }
  std::array<float, 16> to_floats() const;
};
Mat4 operator*(const Mat4& a, const Mat4& b);

enum class NamedView { Top, Front, Side, Iso };
// "top", "front", "side", "iso"; throws std::invalid_argument naming the choices.
NamedView parse_named_view(const std::string& name);

struct WindowPoint {
  double x = 0, y = 0;  // pixels
  double depth = 0;     // 0 near .. 1 far
};

class Camera {
 public:
  // Viewport in pixels (each >= 1).
  void set_viewport(int width, int height);
  int width() const { return width_; }
  int height() const { return height_; }

  // The scene's bounds: the depth range covers them wherever the target is.
  void set_scene(const geometry::Box3& bounds);

  void set_view(NamedView v);
  // Centres the scene's bounds in the current direction with a small margin.
  void fit(const geometry::Box3& bounds);

  // Left drag: dx, dy pixels turn the view (half a degree per pixel).
  void orbit(double dx_pixels, double dy_pixels);
  // Right or middle drag: what was under the cursor follows it.
  void pan(double dx_pixels, double dy_pixels);
  // Wheel: factor > 1 zooms in; the point under the window pixel (x, y)
  // stays under it.
  void zoom_at(double factor, double x, double y);

  double azimuth_deg() const { return azimuth_deg_; }
  double elevation_deg() const { return elevation_deg_; }
  const geometry::Vec3& target() const { return target_; }
  // Half the view's height in mm (the zoom).
  double half_height() const { return half_height_; }
  double mm_per_pixel() const { return 2 * half_height_ / height_; }

  // The screen's right and up and the direction toward the viewer (unit).
  geometry::Vec3 right() const;
  geometry::Vec3 up() const;
  geometry::Vec3 back() const;

  Mat4 view_matrix() const;
  Mat4 projection_matrix() const;
  Mat4 view_projection() const { return projection_matrix() * view_matrix(); }

  WindowPoint project(const geometry::Vec3& world) const;
  // Whether any of the box can be in the view (its projected corners'
  // rectangle meets the viewport): what the renderer skips drawing.
  bool may_see(const geometry::Box3& box) const;
  geometry::Vec3 unproject(const WindowPoint& p) const;

 private:
  double depth_half() const;  // half the depth range around the target

  int width_ = 800, height_ = 600;
  geometry::Vec3 target_{};
  double azimuth_deg_ = 45, elevation_deg_ = 35.264389682754654;
  double half_height_ = 50;
  geometry::Vec3 scene_center_{};
  double scene_radius_ = 100;
};

}  // namespace cncstream::viewer
