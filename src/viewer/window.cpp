// The viewer's GLFW window (see window.hpp).
#include "cncstream/viewer/window.hpp"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>

#include "cncstream/gl/gl_error.hpp"
#include "cncstream/viewer/headless.hpp"
#include "cncstream/viewer/renderer.hpp"

namespace cncstream::viewer {

void LiveCursor::set(const std::function<void(Update&)>& change) {
  std::function<void()> wake;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    change(pending_);
    wake = wake_;
  }
  if (wake) wake();
}

void LiveCursor::set_cutter_position(const geometry::Vec3& tip) {
  set([&](Update& u) { u.cutter = tip; });
}
void LiveCursor::set_progress(double segments_done) {
  set([&](Update& u) { u.progress = segments_done; });
}
void LiveCursor::set_cut(std::shared_ptr<const TriangleMesh> surface) {
  set([&](Update& u) { u.cut = std::move(surface); });
}
void LiveCursor::set_cutter(const cam::Cutter& cutter) {
  set([&](Update& u) { u.tool = cutter; });
}
void LiveCursor::set_status(std::string text) {
  set([&](Update& u) { u.status = std::move(text); });
}

LiveCursor::Update LiveCursor::take() {
  const std::lock_guard<std::mutex> lock(mutex_);
  Update u = pending_;
  pending_ = {};
  return u;
}

void LiveCursor::on_change(std::function<void()> wake) {
  const std::lock_guard<std::mutex> lock(mutex_);
  wake_ = std::move(wake);
}

namespace {

std::string glfw_error_text() {
  const char* text = nullptr;
  glfwGetError(&text);
  return text ? text : "no reason given";
}

// Everything the callbacks change, reached through the window's user pointer.
struct WindowState {
  Scene* scene = nullptr;
  Camera camera;
  Renderer* renderer = nullptr;
  Toolpath* colour_target = nullptr;
  PathColouring colouring = PathColouring::Feed;
  geometry::Box3 bounds;
  double mouse_x = 0, mouse_y = 0;  // framebuffer pixels
  double pixel_scale = 1;           // framebuffer pixels per window unit (HiDPI)
  int dragging = -1;       // the mouse button held, or -1
  bool scrubbing = false;  // the left button went down on the slider
  bool dirty = true;
  bool recolour = false;
};

WindowState& state_of(GLFWwindow* w) { return *static_cast<WindowState*>(glfwGetWindowUserPointer(w)); }

bool on_bar(const WindowState& s, double x, double y) {
  if (!s.scene->program) return false;
  int bx = 0, by = 0, bw = 0, bh = 0;
  Renderer::timeline_bar_rect(s.camera, bx, by, bw, bh);
  return x >= bx - 4 && x <= bx + bw + 4 && y >= by - 6 && y <= by + bh + 6;
}

void scrub_to(WindowState& s, double x) {
  int bx = 0, by = 0, bw = 0, bh = 0;
  Renderer::timeline_bar_rect(s.camera, bx, by, bw, bh);
  s.scene->progress = timeline_at_bar(x, bx, bw, s.scene->program->size());
  s.dirty = true;
}

void on_cursor(GLFWwindow* w, double x, double y) {
  WindowState& s = state_of(w);
  x *= s.pixel_scale;
  y *= s.pixel_scale;
  const double dx = x - s.mouse_x, dy = y - s.mouse_y;
  s.mouse_x = x;
  s.mouse_y = y;
  if (s.scrubbing) scrub_to(s, x);
  else if (s.dragging == GLFW_MOUSE_BUTTON_LEFT) s.camera.orbit(dx, dy);
  else if (s.dragging == GLFW_MOUSE_BUTTON_RIGHT || s.dragging == GLFW_MOUSE_BUTTON_MIDDLE) s.camera.pan(dx, dy);
  s.dirty = true;  // the readout follows the cursor
}

void on_button(GLFWwindow* w, int button, int action, int /*mods*/) {
  WindowState& s = state_of(w);
  if (action == GLFW_PRESS) {
    s.dragging = button;
    s.scrubbing = button == GLFW_MOUSE_BUTTON_LEFT && on_bar(s, s.mouse_x, s.mouse_y);
    if (s.scrubbing) scrub_to(s, s.mouse_x);
  } else {
    s.dragging = -1;
    s.scrubbing = false;
    s.dirty = true;  // a full-resolution frame after a drag
  }
}

void on_scroll(GLFWwindow* w, double /*dx*/, double dy) {
  WindowState& s = state_of(w);
  s.camera.zoom_at(std::pow(1.15, dy), s.mouse_x, s.mouse_y);
  s.dirty = true;
}

void on_key(GLFWwindow* w, int key, int /*scancode*/, int action, int /*mods*/) {
  if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
  WindowState& s = state_of(w);
  Scene& sc = *s.scene;
  auto view = [&](NamedView v) {
    s.camera.set_view(v);
    s.camera.fit(s.bounds);
  };
  switch (key) {
    case GLFW_KEY_1: view(NamedView::Top); break;
    case GLFW_KEY_2: view(NamedView::Front); break;
    case GLFW_KEY_3: view(NamedView::Side); break;
    case GLFW_KEY_4: view(NamedView::Iso); break;
    case GLFW_KEY_F: s.camera.fit(s.bounds); break;
    case GLFW_KEY_C:
      s.colouring = s.colouring == PathColouring::Feed ? PathColouring::Operation : PathColouring::Feed;
      s.recolour = true;
      break;
    case GLFW_KEY_LEFT: sc.progress = timeline_step(sc, -1); break;
    case GLFW_KEY_RIGHT: sc.progress = timeline_step(sc, +1); break;
    case GLFW_KEY_HOME: if (sc.program) sc.progress = 0; break;
    case GLFW_KEY_END: if (sc.program) sc.progress = NAN; break;
    case GLFW_KEY_ESCAPE:
    case GLFW_KEY_Q: glfwSetWindowShouldClose(w, GLFW_TRUE); break;
    default: return;
  }
  s.dirty = true;
}

void on_resize(GLFWwindow* w, int width, int height) {
  if (width < 1 || height < 1) return;  // minimised
  WindowState& s = state_of(w);
  s.camera.set_viewport(width, height);
  int ww = 0, wh = 0;
  glfwGetWindowSize(w, &ww, &wh);
  if (ww > 0) s.pixel_scale = static_cast<double>(width) / ww;
  s.dirty = true;
}

// While a drag moves the view of a large program, frames are drawn at half
// the resolution and scaled up: llvmpipe's time for a frame of lines grows
// with their length in pixels, and a moving view needs speed more than
// detail. The frame after the drag is drawn in full.
class HalfResolution {
 public:
  HalfResolution() = default;
  ~HalfResolution() { release(); }
  HalfResolution(const HalfResolution&) = delete;
  HalfResolution& operator=(const HalfResolution&) = delete;

  void draw(Renderer& renderer, const Camera& full) {
    const int w = std::max(1, full.width() / 2), h = std::max(1, full.height() / 2);
    if (w != w_ || h != h_) create(w, h);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    Camera half = full;
    half.set_viewport(w, h);
    renderer.draw(half);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
    glBlitFramebuffer(0, 0, w, h, 0, 0, full.width(), full.height(), GL_COLOR_BUFFER_BIT, GL_LINEAR);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, full.width(), full.height());
  }

 private:
  void create(int w, int h) {
    release();
    glGenFramebuffers(1, &fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glGenRenderbuffers(2, rb_);
    glBindRenderbuffer(GL_RENDERBUFFER, rb_[0]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w, h);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb_[0]);
    glBindRenderbuffer(GL_RENDERBUFFER, rb_[1]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, w, h);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb_[1]);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    w_ = w;
    h_ = h;
  }
  void release() {
    if (!fbo_) return;
    glDeleteRenderbuffers(2, rb_);
    glDeleteFramebuffers(1, &fbo_);
    fbo_ = 0;
    w_ = h_ = 0;
  }
  GLuint fbo_ = 0, rb_[2] = {0, 0};
  int w_ = 0, h_ = 0;
};
constexpr std::size_t kHalfResolutionVertices = 1'000'000;

// Releases GLFW however run_window ends.
struct GlfwSession {
  GlfwSession() {
    const char* display = std::getenv("DISPLAY");
    const char* wayland = std::getenv("WAYLAND_DISPLAY");
    if ((!display || !*display) && (!wayland || !*wayland))
      throw NoDisplayError(
          "no display to open a window on (DISPLAY is not set): run it on a desktop, under Xvfb "
          "(xvfb-run cncstream view ...), or render one frame without a window with "
          "--screenshot OUT.png --view iso");
    if (!glfwInit()) {
      std::string m = "cannot open a window: ";
      m += glfw_error_text();
      m += "; render without a window with --screenshot OUT.png --view iso";
      throw NoDisplayError(m);
    }
  }
  ~GlfwSession() { glfwTerminate(); }
  GlfwSession(const GlfwSession&) = delete;
  GlfwSession& operator=(const GlfwSession&) = delete;
};

}  // namespace

void run_window(Scene& scene, const WindowOptions& options) {
  const GlfwSession glfw;
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_DEPTH_BITS, 24);
  GLFWwindow* win = glfwCreateWindow(options.width, options.height, options.title.c_str(), nullptr, nullptr);
  if (!win) {
    std::string m = "cannot create an OpenGL 3.3 core window: ";
    m += glfw_error_text();
    throw gl::GlError(m);
  }
  struct WindowCloser {
    GLFWwindow* w;
    ~WindowCloser() { glfwDestroyWindow(w); }
  } closer{win};
  glfwMakeContextCurrent(win);
  glfwSwapInterval(1);

  WindowState s;
  s.scene = &scene;
  s.colouring = options.colouring;
  Renderer renderer;
  HalfResolution half_resolution;  // destroyed before the renderer, with the context current
  s.renderer = &renderer;
  if (scene.program && options.colouring != PathColouring::Feed) colour_toolpath(*scene.program, options.colouring);
  load_scene(renderer, scene);
  int fw = 0, fh = 0;
  glfwGetFramebufferSize(win, &fw, &fh);
  s.bounds = scene.bounds();
  s.camera = camera_for(scene, options.view, std::max(fw, 1), std::max(fh, 1));
  int ww = 0, wh = 0;
  glfwGetWindowSize(win, &ww, &wh);
  if (ww > 0 && fw > 0) s.pixel_scale = static_cast<double>(fw) / ww;

  glfwSetWindowUserPointer(win, &s);
  glfwSetCursorPosCallback(win, on_cursor);
  glfwSetMouseButtonCallback(win, on_button);
  glfwSetScrollCallback(win, on_scroll);
  glfwSetKeyCallback(win, on_key);
  glfwSetFramebufferSizeCallback(win, on_resize);
  if (options.live) options.live->on_change([] { glfwPostEmptyEvent(); });
  struct LiveDetach {
    LiveCursor* live;
    ~LiveDetach() {
      if (live) live->on_change(nullptr);
    }
  } detach{options.live};

  glfwSetWindowRefreshCallback(win, [](GLFWwindow* w) { state_of(w).dirty = true; });
  std::string live_status;
  while (!glfwWindowShouldClose(win)) {
    if (options.live) {
      LiveCursor::Update u = options.live->take();
      if (u.cutter) scene.cutter_at = u.cutter, s.dirty = true;
      if (u.progress) scene.progress = *u.progress, s.dirty = true;
      if (u.cut) {
        if (!scene.cut) scene.cut.emplace();
        scene.cut->mesh = *u.cut;
        renderer.set_cut(scene.cut->mesh);
        s.dirty = true;
      }
      if (u.tool) {
        scene.cutter = *u.tool;
        renderer.set_cutter(cutter_surface(*scene.cutter, {}));
        s.dirty = true;
      }
      if (u.status) live_status = std::move(*u.status), s.dirty = true;
    }
    if (!s.dirty) {
      // Input and LiveCursor's wake-ups end the wait; the timeout is a
      // safety net for a wake-up lost to the X server.
      glfwWaitEventsTimeout(1.0);
      continue;
    }
    s.dirty = false;
    if (s.recolour && scene.program) {
      colour_toolpath(*scene.program, s.colouring);
      renderer.recolour_toolpath(*scene.program);
    }
    s.recolour = false;
    if (scene.program) renderer.set_progress(*scene.program, scene.progress);
    renderer.set_cutter_position(scene.cutter_tip());
    const bool half = s.dragging >= 0 && !s.scrubbing && renderer.toolpath_vertices() > kHalfResolutionVertices;
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (half) half_resolution.draw(renderer, s.camera);
    else renderer.draw(s.camera);
    // The readout: the depth under the cursor before the slider covers it
    // (none while a drag draws at half resolution: no depth in the window).
    std::string title = options.title;
    if (!live_status.empty()) title += "  |  " + live_status;
    const int px = static_cast<int>(s.mouse_x), py = static_cast<int>(s.mouse_y);
    if (!half && px >= 0 && py >= 0 && px < s.camera.width() && py < s.camera.height()) {
      float depth = 1.0f;
      glReadPixels(px, s.camera.height() - 1 - py, 1, 1, GL_DEPTH_COMPONENT, GL_FLOAT, &depth);
      if (depth < 1.0f) {
        title += "  |  ";
        title += format_position(s.camera.unproject({s.mouse_x + 0.5, s.mouse_y + 0.5, depth}));
      }
    }
    if (scene.program) {
      title += "  |  ";
      title += format_progress(*scene.program, scene.progress);
      const double n = static_cast<double>(scene.program->size());
      renderer.draw_timeline_bar(s.camera, n > 0 && !std::isnan(scene.progress) ? scene.progress / n : 1.0);
    }
    glfwSetWindowTitle(win, title.c_str());
    glfwSwapBuffers(win);
    if (options.after_frame && !options.after_frame(title)) glfwSetWindowShouldClose(win, GLFW_TRUE);
  }
}

}  // namespace cncstream::viewer
