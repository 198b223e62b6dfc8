#pragma once
// A GLSL program from a vertex and a fragment shader, for the depth-buffer
// CL engine and the viewer. Needs a current context; throws GlError naming
// `what` and the compiler's log when a shader does not compile or the
// program does not link.
#include <string_view>

namespace cncstream::gl {

// The program's GL name (a GLuint).
unsigned int link_shader_program(const char* vertex_source, const char* fragment_source, std::string_view what);

}  // namespace cncstream::gl
