#pragma once
// The renderer without a window: an OpenGL 3.3 core context on EGL's
// surfaceless platform (gl/egl_context.hpp; no X server), drawing into a
// framebuffer object read back as an image. For `cncstream view
// --screenshot`, the tests and the benchmarks.
#include <memory>
#include <string>

#include "cncstream/image/deviation_map.hpp"
#include "cncstream/image/image.hpp"
#include "cncstream/viewer/camera.hpp"
#include "cncstream/viewer/renderer.hpp"
#include "cncstream/viewer/scene.hpp"

namespace cncstream::viewer {

class HeadlessView {
 public:
  // Throws gl::GlError naming what failed when no context can be made, and
  // std::invalid_argument for a size outside 1..8192.
  HeadlessView(int width, int height, int egl_platform = 0x31DD /* EGL_PLATFORM_SURFACELESS_MESA */);
  ~HeadlessView();
  HeadlessView(const HeadlessView&) = delete;
  HeadlessView& operator=(const HeadlessView&) = delete;

  int width() const { return width_; }
  int height() const { return height_; }
  Renderer& renderer() { return *renderer_; }
  // "llvmpipe (LLVM 15.0.6, 256 bits) | 4.5 (Core Profile) Mesa 22.3.6"
  const std::string& gl_renderer() const;

  // Draws the loaded layers from `camera` (its viewport is this view's size)
  // and waits for the frame to finish.
  void draw(const Camera& camera);
  // The last frame, top row first.
  image::RgbImage read_image() const;
  // The last frame's depth at window pixel (x, y), 0 near .. 1 far (1:
  // nothing there).
  double depth_at(int x, int y) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::unique_ptr<Renderer> renderer_;
  int width_, height_;
};

// Uploads every layer of `scene` (the cutter's mesh at the origin, placed
// at scene.cutter_tip()).
void load_scene(Renderer& renderer, const Scene& scene);

// A camera on the scene from a named view, fitted to it, width x height.
Camera camera_for(const Scene& scene, NamedView view, int width, int height);

// One frame of the scene from a named view, fitted: --screenshot. With a
// cut, and room for it (height at least deviation_legend_size's), the
// deviation map's legend stands at the right and the view is narrower.
image::RgbImage screenshot(const Scene& scene, NamedView view, int width, int height, std::string* gl_renderer = nullptr);

// The deviation map's legend for a cut (image/deviation_map.hpp).
image::DeviationLegend legend_of(const CutSurface& cut);

}  // namespace cncstream::viewer
