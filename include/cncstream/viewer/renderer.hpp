#pragma once
// The viewer's OpenGL 3.3 core renderer: one buffer per layer (part, cut,
// program, cutter), uploaded once; the program's lines with rapids dashed
// and the timeline as a draw range (segments before it bright, after it
// dim); the surfaces Phong-shaded with a headlight. The same renderer draws
// into a window (window.hpp) and into an offscreen framebuffer (headless.hpp).
//
// Needs a current OpenGL 3.3 core context on the calling thread for its
// whole life; throws gl::GlError when a shader does not compile.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>

#include "cncstream/gl/gl_error.hpp"
#include "cncstream/image/image.hpp"
#include "cncstream/viewer/camera.hpp"
#include "cncstream/viewer/scene_mesh.hpp"
#include "cncstream/viewer/toolpath_buffers.hpp"

namespace cncstream::viewer {

inline constexpr image::Rgb kBackground{245, 246, 248};

class Renderer {
 public:
  Renderer();
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  void set_part(const TriangleMesh& mesh);
  void set_cut(const TriangleMesh& mesh);
  // The cutter's mesh with its tip at the origin; drawn at set_cutter_position.
  void set_cutter(const TriangleMesh& mesh_at_origin);
  void set_toolpath(const Toolpath& path);
  // After colour_toolpath: the path uploaded again, the timeline kept.
  void recolour_toolpath(const Toolpath& path);

  // Timeline: segments before `segments_done` of `path` (the one uploaded)
  // bright, the rest dim; NaN: all bright.
  void set_progress(const Toolpath& path, double segments_done);
  void set_cutter_position(std::optional<geometry::Vec3> tip) { cutter_at_ = tip; }

  void draw(const Camera& camera);
  // A slider along the window's bottom edge, `fraction` of it filled.
  void draw_timeline_bar(const Camera& camera, double fraction);
  // The timeline bar's rectangle in window pixels (x, y top-left, w, h).
  static void timeline_bar_rect(const Camera& camera, int& x, int& y, int& w, int& h);

  std::size_t toolpath_vertices() const { return path_vertices_; }
  // Vertices in the strip drawn at a distance (display_strip).
  std::size_t toolpath_distant_vertices() const { return distant_vertices_; }
  // The tolerance of that strip, mm; it is drawn when a pixel is at least
  // twice as large.
  double distant_tolerance() const { return distant_tolerance_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::size_t path_vertices_ = 0, distant_vertices_ = 0;
  double distant_tolerance_ = 0;
  std::size_t bright_vertices_ = SIZE_MAX;
  std::optional<geometry::Vec3> cutter_at_;
};

}  // namespace cncstream::viewer
