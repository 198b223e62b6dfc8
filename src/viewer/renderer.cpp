// The viewer's GL 3.3 core renderer (see renderer.hpp).
#include "cncstream/viewer/renderer.hpp"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "cncstream/gl/shader_program.hpp"

namespace cncstream::viewer {

namespace {

// A vertex attribute's place in the bound buffer: OpenGL takes the byte
// offset as a pointer (its API's convention since buffer objects).
const void* byte_offset(std::size_t bytes) {
  return reinterpret_cast<const void*>(bytes);  // NOLINT(performance-no-int-to-ptr): see above
}

const char* const kMeshVertex = R"(#version 330 core
layout(location = 0) in vec3 pos;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec4 colour;
uniform mat4 vp;
uniform vec3 offset;  // the cutter's tip; 0 for the other surfaces
out vec3 v_normal;
out vec3 v_colour;
void main() {
  gl_Position = vp * vec4(pos + offset, 1.0);
  v_normal = normal;
  v_colour = colour.rgb;
}
)";

// Two-sided headlight: an STL's winding says nothing reliable.
const char* const kMeshFragment = R"(#version 330 core
in vec3 v_normal;
in vec3 v_colour;
uniform vec3 light;      // toward the viewer, world space
uniform float specular;  // 0: colours exact where a surface faces the viewer
out vec4 frag;
void main() {
  float len = length(v_normal);
  float d = len > 0.0 ? abs(dot(v_normal / len, light)) : 1.0;
  vec3 c = v_colour * (0.35 + 0.65 * d) + vec3(specular * pow(d, 40.0));
  frag = vec4(min(c, vec3(1.0)), 1.0);
}
)";

// The path is a line strip: a line takes its colour and kind from its end
// vertex (GL's provoking vertex for flat attributes, the last by default).
const char* const kPathVertex = R"(#version 330 core
layout(location = 0) in vec3 pos;
layout(location = 1) in float along;
layout(location = 2) in vec4 colour;  // rgb, and a: 0 cut, 0.5 hidden jump, 1 rapid
layout(location = 3) in int index;    // the distant strip: the vertex's index in the whole strip
uniform bool indexed;                 // read index (else the whole strip: gl_VertexID)
uniform mat4 vp;
uniform int bright_vertices;  // the timeline: lines ending before it are done
uniform vec3 background;
out float v_along;
flat out float v_kind;
flat out vec3 v_colour;
void main() {
  gl_Position = vp * vec4(pos, 1.0);
  gl_Position.z -= 2e-4 * gl_Position.w;  // a path on a surface stays in front of it
  v_along = along;
  v_kind = colour.a;
  int id = indexed ? index : gl_VertexID;
  v_colour = id < bright_vertices ? colour.rgb : mix(colour.rgb, background, 0.8);
}
)";

const char* const kPathFragment = R"(#version 330 core
in float v_along;
flat in float v_kind;
flat in vec3 v_colour;
uniform float dash;  // mm per dash and gap
out vec4 frag;
void main() {
  if (v_kind > 0.25 && v_kind < 0.75) discard;
  if (v_kind > 0.75 && fract(v_along / dash) > 0.5) discard;
  frag = vec4(v_colour, 1.0);
}
)";

const char* const kOverlayVertex = R"(#version 330 core
layout(location = 0) in vec2 pos;  // window pixels, y down
uniform vec2 viewport;
void main() { gl_Position = vec4(pos.x / viewport.x * 2.0 - 1.0, 1.0 - pos.y / viewport.y * 2.0, 0.0, 1.0); }
)";

const char* const kOverlayFragment = R"(#version 330 core
uniform vec3 colour;
out vec4 frag;
void main() { frag = vec4(colour, 1.0); }
)";

// A run of a line strip and its bounds: zoomed in, the renderer draws only
// the runs that may be in view (a strip of millions of vertices costs
// llvmpipe its vertex shading even where nothing is seen).
struct StripRun {
  GLint first = 0;
  GLsizei count = 0;
  geometry::Box3 box;
};
constexpr std::size_t kRunVertices = 16384;

struct Layer {
  GLuint vao = 0, vbo = 0, ebo = 0;
  GLsizei count = 0;  // indices (surfaces) or vertices (lines)
  std::vector<StripRun> runs;  // line strips
  void release() {
    if (ebo) glDeleteBuffers(1, &ebo);
    if (vbo) glDeleteBuffers(1, &vbo);
    if (vao) glDeleteVertexArrays(1, &vao);
    vao = vbo = ebo = 0;
    count = 0;
    runs.clear();
  }
};

// Runs of kRunVertices lines; each takes the next run's first vertex too,
// so the line between them is drawn.
template <class PositionOf>
std::vector<StripRun> strip_runs(std::size_t n, PositionOf position_of) {
  std::vector<StripRun> runs;
  for (std::size_t first = 0; first + 1 < n; first += kRunVertices) {
    const std::size_t end = std::min(first + kRunVertices + 1, n);
    StripRun r;
    r.first = static_cast<GLint>(first);
    r.count = static_cast<GLsizei>(end - first);
    for (std::size_t v = first; v < end; ++v) r.box.add(position_of(v));
    runs.push_back(r);
  }
  return runs;
}

// Draws the runs the camera may see, adjacent ones in one call.
void draw_visible_runs(const Layer& l, const Camera& camera) {
  GLint first = -1;
  GLsizei count = 0;
  for (const StripRun& r : l.runs) {
    if (!camera.may_see(r.box)) continue;
    if (first >= 0 && first + count - 1 == r.first) {
      count = r.first + r.count - first;  // continues the previous run
      continue;
    }
    if (first >= 0) glDrawArrays(GL_LINE_STRIP, first, count);
    first = r.first;
    count = r.count;
  }
  if (first >= 0) glDrawArrays(GL_LINE_STRIP, first, count);
}

void upload_mesh(Layer& layer, const TriangleMesh& mesh) {
  layer.release();
  if (mesh.indices.empty()) return;
  glGenVertexArrays(1, &layer.vao);
  glBindVertexArray(layer.vao);
  glGenBuffers(1, &layer.vbo);
  glBindBuffer(GL_ARRAY_BUFFER, layer.vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(mesh.vertices.size() * sizeof(MeshVertex)),
               mesh.vertices.data(), GL_STATIC_DRAW);
  glGenBuffers(1, &layer.ebo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, layer.ebo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(mesh.indices.size() * sizeof(std::uint32_t)),
               mesh.indices.data(), GL_STATIC_DRAW);
  constexpr auto stride = static_cast<GLsizei>(sizeof(MeshVertex));
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, byte_offset(offsetof(MeshVertex, x)));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride, byte_offset(offsetof(MeshVertex, nx)));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 4, GL_UNSIGNED_BYTE, GL_TRUE, stride, byte_offset(offsetof(MeshVertex, r)));
  glBindVertexArray(0);
  layer.count = static_cast<GLsizei>(mesh.indices.size());
}

void set_matrix(GLuint program, const char* name, const Mat4& m) {
  const auto f = m.to_floats();
  glUniformMatrix4fv(glGetUniformLocation(program, name), 1, GL_FALSE, f.data());
}

// The distant strip's vertex: a copy of the whole strip's, with its index
// there (for the timeline). A buffer of its own: llvmpipe shades every
// vertex between the lowest and highest index of an indexed draw, so
// indices into the whole strip would save nothing.
struct DistantVertex {
  PathVertex v;
  std::int32_t index = 0;
};

void path_attributes(GLsizei stride) {
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, byte_offset(offsetof(PathVertex, x)));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 1, GL_FLOAT, GL_FALSE, stride, byte_offset(offsetof(PathVertex, along)));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 4, GL_UNSIGNED_BYTE, GL_TRUE, stride, byte_offset(offsetof(PathVertex, r)));
}

}  // namespace

struct Renderer::Impl {
  GLuint mesh_program = 0, path_program = 0, overlay_program = 0;
  Layer part, cut, cutter, path, distant;
  GLuint overlay_vao = 0, overlay_vbo = 0;
};

Renderer::Renderer() : impl_(std::make_unique<Impl>()) {
  impl_->mesh_program = gl::link_shader_program(kMeshVertex, kMeshFragment, "viewer's surface");
  impl_->path_program = gl::link_shader_program(kPathVertex, kPathFragment, "viewer's tool path");
  impl_->overlay_program = gl::link_shader_program(kOverlayVertex, kOverlayFragment, "viewer's overlay");
  glGenVertexArrays(1, &impl_->overlay_vao);
  glBindVertexArray(impl_->overlay_vao);
  glGenBuffers(1, &impl_->overlay_vbo);
  glBindBuffer(GL_ARRAY_BUFFER, impl_->overlay_vbo);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 0, nullptr);
  glBindVertexArray(0);
}

Renderer::~Renderer() {
  for (Layer* l : {&impl_->part, &impl_->cut, &impl_->cutter, &impl_->path, &impl_->distant}) l->release();
  glDeleteBuffers(1, &impl_->overlay_vbo);
  glDeleteVertexArrays(1, &impl_->overlay_vao);
  glDeleteProgram(impl_->mesh_program);
  glDeleteProgram(impl_->path_program);
  glDeleteProgram(impl_->overlay_program);
}

void Renderer::set_part(const TriangleMesh& mesh) { upload_mesh(impl_->part, mesh); }
void Renderer::set_cut(const TriangleMesh& mesh) { upload_mesh(impl_->cut, mesh); }
void Renderer::set_cutter(const TriangleMesh& mesh) { upload_mesh(impl_->cutter, mesh); }

void Renderer::set_toolpath(const Toolpath& path) {
  Layer& l = impl_->path;
  l.release();
  impl_->distant.release();
  path_vertices_ = path.vertices.size();
  distant_vertices_ = 0;
  bright_vertices_ = SIZE_MAX;
  if (path.vertices.empty()) return;
  glGenVertexArrays(1, &l.vao);
  glBindVertexArray(l.vao);
  glGenBuffers(1, &l.vbo);
  glBindBuffer(GL_ARRAY_BUFFER, l.vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(path.vertices.size() * sizeof(PathVertex)),
               path.vertices.data(), GL_STATIC_DRAW);
  path_attributes(static_cast<GLsizei>(sizeof(PathVertex)));
  l.count = static_cast<GLsizei>(path.vertices.size());
  l.runs = strip_runs(path.vertices.size(), [&](std::size_t v) {
    const PathVertex& p = path.vertices[v];
    return geometry::Vec3{p.x, p.y, p.z};
  });
  // The strip for distant views: lossless below half a pixel (display_strip).
  distant_tolerance_ = std::max(norm(path.bounds.size()) / 8000, 1e-4);
  std::vector<DistantVertex> distant;
  for (const std::uint32_t v : display_strip(path, distant_tolerance_))
    distant.push_back({path.vertices[v], static_cast<std::int32_t>(v)});
  Layer& d = impl_->distant;
  glGenVertexArrays(1, &d.vao);
  glBindVertexArray(d.vao);
  glGenBuffers(1, &d.vbo);
  glBindBuffer(GL_ARRAY_BUFFER, d.vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(distant.size() * sizeof(DistantVertex)), distant.data(),
               GL_STATIC_DRAW);
  path_attributes(static_cast<GLsizei>(sizeof(DistantVertex)));
  glEnableVertexAttribArray(3);
  glVertexAttribIPointer(3, 1, GL_INT, static_cast<GLsizei>(sizeof(DistantVertex)),
                         byte_offset(offsetof(DistantVertex, index)));
  d.count = static_cast<GLsizei>(distant.size());
  d.runs = strip_runs(distant.size(), [&](std::size_t v) {
    const PathVertex& p = distant[v].v;
    return geometry::Vec3{p.x, p.y, p.z};
  });
  distant_vertices_ = distant.size();
  glBindVertexArray(0);
}

void Renderer::set_progress(const Toolpath& path, double segments_done) {
  bright_vertices_ = std::isnan(segments_done) ? SIZE_MAX : path.vertices_done(segments_done);
}

void Renderer::recolour_toolpath(const Toolpath& path) {
  // Uploaded again: the distant strip merges lines of one colour only.
  const std::size_t bright = bright_vertices_;
  set_toolpath(path);
  bright_vertices_ = bright;
}

void Renderer::draw(const Camera& camera) {
  glViewport(0, 0, camera.width(), camera.height());
  glClearColor(kBackground.r / 255.0f, kBackground.g / 255.0f, kBackground.b / 255.0f, 1.0f);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  const Mat4 vp = camera.view_projection();
  const geometry::Vec3 light = camera.back();

  const GLuint mp = impl_->mesh_program;
  glUseProgram(mp);
  set_matrix(mp, "vp", vp);
  glUniform3f(glGetUniformLocation(mp, "light"), static_cast<float>(light.x), static_cast<float>(light.y),
              static_cast<float>(light.z));
  auto draw_mesh = [&](const Layer& l, const geometry::Vec3& offset, float specular) {
    if (!l.count) return;
    glUniform3f(glGetUniformLocation(mp, "offset"), static_cast<float>(offset.x), static_cast<float>(offset.y),
                static_cast<float>(offset.z));
    glUniform1f(glGetUniformLocation(mp, "specular"), specular);
    glBindVertexArray(l.vao);
    glDrawElements(GL_TRIANGLES, l.count, GL_UNSIGNED_INT, nullptr);
  };
  draw_mesh(impl_->part, {}, 0.12f);
  draw_mesh(impl_->cut, {}, 0.0f);  // the deviation colours stay readable
  if (cutter_at_) draw_mesh(impl_->cutter, *cutter_at_, 0.1f);

  if (impl_->path.count) {
    const GLuint pp = impl_->path_program;
    glUseProgram(pp);
    set_matrix(pp, "vp", vp);
    const std::size_t bright = std::min(bright_vertices_, path_vertices_);
    glUniform1i(glGetUniformLocation(pp, "bright_vertices"), static_cast<GLint>(bright));
    glUniform3f(glGetUniformLocation(pp, "background"), kBackground.r / 255.0f, kBackground.g / 255.0f,
                kBackground.b / 255.0f);
    // Dashes about 6 pixels long whatever the zoom.
    glUniform1f(glGetUniformLocation(pp, "dash"), static_cast<float>(12 * camera.mm_per_pixel()));
    const bool far = camera.mm_per_pixel() >= 2 * distant_tolerance_ && impl_->distant.count > 1;
    const Layer& l = far ? impl_->distant : impl_->path;
    glUniform1i(glGetUniformLocation(pp, "indexed"), far ? 1 : 0);
    glBindVertexArray(l.vao);
    draw_visible_runs(l, camera);
  }
  glBindVertexArray(0);
}

void Renderer::timeline_bar_rect(const Camera& camera, int& x, int& y, int& w, int& h) {
  x = 16;
  w = std::max(camera.width() - 32, 1);
  h = 10;
  y = camera.height() - 24;
}

void Renderer::draw_timeline_bar(const Camera& camera, double fraction) {
  int x = 0, y = 0, w = 0, h = 0;
  timeline_bar_rect(camera, x, y, w, h);
  fraction = std::clamp(std::isnan(fraction) ? 1.0 : fraction, 0.0, 1.0);
  glDisable(GL_DEPTH_TEST);
  const GLuint op = impl_->overlay_program;
  glUseProgram(op);
  glUniform2f(glGetUniformLocation(op, "viewport"), static_cast<float>(camera.width()),
              static_cast<float>(camera.height()));
  glBindVertexArray(impl_->overlay_vao);
  glBindBuffer(GL_ARRAY_BUFFER, impl_->overlay_vbo);
  auto rect = [&](double rx, double ry, double rw, double rh, float r, float g, float b) {
    const auto x0 = static_cast<float>(rx), y0 = static_cast<float>(ry), x1 = static_cast<float>(rx + rw),
               y1 = static_cast<float>(ry + rh);
    const std::array<float, 12> v{x0, y0, x1, y0, x1, y1, x0, y0, x1, y1, x0, y1};
    glBufferData(GL_ARRAY_BUFFER, sizeof(v), v.data(), GL_STREAM_DRAW);
    glUniform3f(glGetUniformLocation(op, "colour"), r, g, b);
    glDrawArrays(GL_TRIANGLES, 0, 6);
  };
  rect(x, y, w, h, 0.78f, 0.80f, 0.84f);
  rect(x, y, w * fraction, h, 0.25f, 0.45f, 0.75f);
  rect(x + w * fraction - 3, y - 4, 6, h + 8, 0.15f, 0.15f, 0.2f);  // the knob
  glBindVertexArray(0);
  glEnable(GL_DEPTH_TEST);
}

}  // namespace cncstream::viewer
