// Offscreen rendering on the EGL surfaceless context (see headless.hpp).
#include "cncstream/viewer/headless.hpp"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <fmt/core.h>

#include <algorithm>
#include <optional>
#include <stdexcept>
#include <vector>

#include "cncstream/gl/egl_context.hpp"
#include "cncstream/gl/gl_error.hpp"

namespace cncstream::viewer {

struct HeadlessView::Impl {
  std::unique_ptr<gl::EglContext> context;
  GLuint fbo = 0, colour = 0, depth = 0;
};

HeadlessView::HeadlessView(int width, int height, int egl_platform)
    : impl_(std::make_unique<Impl>()), width_(width), height_(height) {
  if (width < 1 || height < 1 || width > 8192 || height > 8192)
    throw std::invalid_argument(fmt::format("viewer: a screenshot of {} x {} pixels: each side must be 1..8192",
                                            width, height));
  impl_->context = std::make_unique<gl::EglContext>(egl_platform);
  glGenFramebuffers(1, &impl_->fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, impl_->fbo);
  glGenRenderbuffers(1, &impl_->colour);
  glBindRenderbuffer(GL_RENDERBUFFER, impl_->colour);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, impl_->colour);
  glGenRenderbuffers(1, &impl_->depth);
  glBindRenderbuffer(GL_RENDERBUFFER, impl_->depth);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, width, height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, impl_->depth);
  const GLenum st = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (st != GL_FRAMEBUFFER_COMPLETE)
    throw gl::GlError(fmt::format("OpenGL: the viewer's {}x{} framebuffer is incomplete (status 0x{:04X})", width,
                                  height, st));
  renderer_ = std::make_unique<Renderer>();
}

HeadlessView::~HeadlessView() {
  renderer_.reset();  // its buffers go while the context is current
  glDeleteRenderbuffers(1, &impl_->depth);
  glDeleteRenderbuffers(1, &impl_->colour);
  glDeleteFramebuffers(1, &impl_->fbo);
}

const std::string& HeadlessView::gl_renderer() const { return impl_->context->renderer(); }

void HeadlessView::draw(const Camera& camera) {
  if (camera.width() != width_ || camera.height() != height_)
    throw std::invalid_argument("viewer: the camera's viewport is not the screenshot's size");
  glBindFramebuffer(GL_FRAMEBUFFER, impl_->fbo);
  renderer_->draw(camera);
  glFinish();
  const GLenum err = glGetError();
  if (err != GL_NO_ERROR) throw gl::GlError(fmt::format("OpenGL: drawing the view failed (GL error 0x{:04X})", err));
}

image::RgbImage HeadlessView::read_image() const {
  std::vector<std::uint8_t> px(static_cast<std::size_t>(width_) * height_ * 4);
  glBindFramebuffer(GL_FRAMEBUFFER, impl_->fbo);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, px.data());
  image::RgbImage img(width_, height_);
  for (int y = 0; y < height_; ++y)
    for (int x = 0; x < width_; ++x) {
      // GL's rows run bottom-up.
      const std::size_t k = (static_cast<std::size_t>(height_ - 1 - y) * width_ + x) * 4;
      img.set(x, y, {px[k], px[k + 1], px[k + 2]});
    }
  return img;
}

double HeadlessView::depth_at(int x, int y) const {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return 1.0;
  float d = 1.0f;
  glBindFramebuffer(GL_FRAMEBUFFER, impl_->fbo);
  glReadPixels(x, height_ - 1 - y, 1, 1, GL_DEPTH_COMPONENT, GL_FLOAT, &d);
  return d;
}

void load_scene(Renderer& renderer, const Scene& scene) {
  if (scene.part) renderer.set_part(*scene.part);
  if (scene.cut) renderer.set_cut(scene.cut->mesh);
  if (scene.program) renderer.set_toolpath(*scene.program);
  if (scene.cutter) renderer.set_cutter(cutter_surface(*scene.cutter, {}));
  renderer.set_cutter_position(scene.cutter_tip());
  if (scene.program) renderer.set_progress(*scene.program, scene.progress);
}

Camera camera_for(const Scene& scene, NamedView view, int width, int height) {
  Camera cam;
  cam.set_viewport(width, height);
  const geometry::Box3 b = scene.bounds();
  cam.set_scene(b);
  cam.set_view(view);
  cam.fit(b);
  return cam;
}

image::DeviationLegend legend_of(const CutSurface& cut) {
  const cam::DeviationStats& st = cut.stats;
  image::DeviationLegend l;
  l.tolerance = st.tolerance;
  l.lo = st.has_gouge ? std::min(0.0, st.largest_gouge.value) : 0.0;
  l.hi = std::max(0.0, st.largest_excess.value);
  if (l.lo < 0) l.lo_at = fmt::format("at x {:.2f} y {:.2f}", st.largest_gouge.x, st.largest_gouge.y);
  if (l.hi > 0) l.hi_at = fmt::format("at x {:.2f} y {:.2f}", st.largest_excess.x, st.largest_excess.y);
  l.gouged = st.gouged;
  l.excess = st.excess;
  l.on_part = st.on_part;
  return l;
}

image::RgbImage screenshot(const Scene& scene, NamedView view, int width, int height, std::string* gl_renderer) {
  std::optional<image::DeviationLegend> legend;
  int legend_w = 0;
  if (scene.cut && scene.cut->stats.tolerance > 0) {  // compared with a design (not a bare stock)
    legend = legend_of(*scene.cut);
    const auto [w, h] = image::deviation_legend_size(*legend);
    if (h + 32 <= height && w + 32 < width / 2) legend_w = w + 32;
    else legend.reset();  // no room: the view alone
  }
  const int view_w = width - legend_w;
  HeadlessView hv(view_w, height);
  if (gl_renderer) *gl_renderer = hv.gl_renderer();
  load_scene(hv.renderer(), scene);
  hv.draw(camera_for(scene, view, view_w, height));
  if (!legend) return hv.read_image();
  image::RgbImage out(width, height, kBackground);
  out.blit(hv.read_image(), 0, 0);
  image::draw_deviation_legend(out, view_w + 16, 16, *legend);
  return out;
}

}  // namespace cncstream::viewer
