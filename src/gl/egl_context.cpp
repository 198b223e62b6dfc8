#include "cncstream/gl/egl_context.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/gl.h>

#include <fmt/core.h>

#include "cncstream/gl/gl_error.hpp"

namespace cncstream::gl {

namespace {

std::string egl_error_text() { return fmt::format("0x{:04X}", static_cast<unsigned>(eglGetError())); }

[[noreturn]] void fail(const char* what) {
  std::string m = "OpenGL context: ";
  m += what;
  m += " (EGL error ";
  m += egl_error_text();
  m += "); headless rendering (the GL CL engine, the viewer's screenshots) needs EGL with Mesa's surfaceless platform and OpenGL 3.3 core (llvmpipe will do)";
  throw GlError(m);
}

}  // namespace

EglContext::EglContext(int platform) {
  const char* client_ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (!client_ext || !get_display) fail("no EGL display: eglGetPlatformDisplayEXT is not available");
  EGLDisplay dpy = get_display(static_cast<EGLenum>(platform), EGL_DEFAULT_DISPLAY, nullptr);
  if (dpy == EGL_NO_DISPLAY) fail("no EGL display for the surfaceless platform");
  EGLint major = 0, minor = 0;
  if (!eglInitialize(dpy, &major, &minor)) fail("no EGL display: eglInitialize failed");
  display_ = dpy;
  if (!eglBindAPI(EGL_OPENGL_API)) {
    eglTerminate(dpy);
    fail("EGL cannot bind the desktop OpenGL API");
  }
  const EGLint config_attribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint count = 0;
  if (!eglChooseConfig(dpy, config_attribs, &config, 1, &count) || count < 1) {
    eglTerminate(dpy);
    fail("no EGL config for desktop OpenGL");
  }
  const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3,
                                    EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                    EGL_NONE};
  EGLContext ctx = eglCreateContext(dpy, config, EGL_NO_CONTEXT, context_attribs);
  if (ctx == EGL_NO_CONTEXT) {
    eglTerminate(dpy);
    fail("no OpenGL 3.3 core context");
  }
  context_ = ctx;
  if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
    eglDestroyContext(dpy, ctx);
    eglTerminate(dpy);
    fail("cannot make the context current without a surface (EGL_KHR_surfaceless_context)");
  }
  const auto* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const auto* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  renderer_ = r ? r : "?";
  renderer_ += " | ";
  renderer_ += v ? v : "?";
}

EglContext::~EglContext() {
  eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(display_, context_);
  eglTerminate(display_);
}

}  // namespace cncstream::gl
