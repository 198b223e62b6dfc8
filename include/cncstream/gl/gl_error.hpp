#pragma once
// What the GL CL engine throws when it cannot get or use a GL context (no EGL
// display, no config, no 3.3 core context, an incomplete framebuffer, a shader
// that does not compile): the message names the step that failed.
#include <stdexcept>

namespace cncstream::gl {

class GlError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace cncstream::gl
