#include "cncstream/gl/shader_program.hpp"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <fmt/core.h>

#include <array>

#include "cncstream/gl/gl_error.hpp"

namespace cncstream::gl {

namespace {

GLuint compile(GLenum kind, const char* src, std::string_view what) {
  const GLuint s = glCreateShader(kind);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    std::array<char, 2048> log{};
    glGetShaderInfoLog(s, static_cast<GLsizei>(log.size()), nullptr, log.data());
    glDeleteShader(s);
    throw GlError(fmt::format("OpenGL: the {} {} shader does not compile: {}", what,
                              kind == GL_VERTEX_SHADER ? "vertex" : "fragment", log.data()));
  }
  return s;
}

}  // namespace

unsigned int link_shader_program(const char* vertex_source, const char* fragment_source, std::string_view what) {
  const GLuint vs = compile(GL_VERTEX_SHADER, vertex_source, what);
  GLuint fs = 0;
  try {
    fs = compile(GL_FRAGMENT_SHADER, fragment_source, what);
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  const GLuint p = glCreateProgram();
  glAttachShader(p, vs);
  glAttachShader(p, fs);
  glLinkProgram(p);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    std::array<char, 2048> log{};
    glGetProgramInfoLog(p, static_cast<GLsizei>(log.size()), nullptr, log.data());
    glDeleteProgram(p);
    throw GlError(fmt::format("OpenGL: the {} shader program does not link: {}", what, log.data()));
  }
  return p;
}

}  // namespace cncstream::gl
