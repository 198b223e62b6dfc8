#pragma once
// A headless OpenGL 3.3 core context: EGL on Mesa's surfaceless platform (no
// X server, no window; llvmpipe without a GPU, the GPU's driver with one),
// made current on the calling thread with no surface. Throws GlError naming
// the step that failed. Used by the GL CL engine and the viewer's
// screenshots (src/viewer/).
#include <string>

namespace cncstream::gl {

class EglContext {
 public:
  // platform: the EGL platform enum (EGL_PLATFORM_SURFACELESS_MESA); tests
  // pass a bad one to see the error.
  explicit EglContext(int platform);
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  // "llvmpipe (LLVM 15.0.6, 256 bits) | 4.5 (Core Profile) Mesa 22.3.6"
  const std::string& renderer() const { return renderer_; }

 private:
  void* display_ = nullptr;
  void* context_ = nullptr;
  std::string renderer_;
};

}  // namespace cncstream::gl
