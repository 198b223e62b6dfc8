#include "cncstream/gl/gl_cl_engine.hpp"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include "cncstream/gl/offset_tessellation.hpp"
#include "cncstream/gl/egl_context.hpp"
#include "cncstream/gl/shader_program.hpp"

namespace cncstream::gl {

namespace {

// A vertex attribute's place in the bound buffer: OpenGL takes the byte offset
// as a pointer (its API's convention since buffer objects replaced arrays).
const void* buffer_offset(std::size_t floats) {
  return reinterpret_cast<const void*>(floats * sizeof(float));  // NOLINT(performance-no-int-to-ptr): see above
}

// ---------------------------------------------------------------- shaders

const char* const kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 pos;     // relative mm (the cap's own frame for vertex offsets)
layout(location = 1) in vec3 offset;  // the cap's vertex, relative mm (0 for other triangles)
layout(location = 2) in vec3 plane0;  // trim: the facet's prism as half-planes a*x + b*y + c >= 0
layout(location = 3) in vec3 plane1;
layout(location = 4) in vec3 plane2;
layout(location = 5) in vec2 zrange;  // the triangle's lowest and highest z (before offset)
layout(location = 6) in vec4 ref;     // reference point in window pixels, as float hi + lo
layout(location = 7) in vec3 plane;   // z at q0 (before offset), dz/dx, dz/dy (mm per mm)
layout(location = 8) in vec2 q0;      // where plane.x holds, mm from ref
layout(location = 9) in vec4 src;     // the source primitive's other corners s1, s2, mm from ref (see Source)
layout(location = 10) in float reach2; // squared XY reach from the source, mm^2
uniform vec4 xy_map;   // ndc.xy = p.xy * xy_map.xy + xy_map.zw
uniform float z_map;   // ndc.z = p.z * z_map (p.z relative to the middle of the depth range)
uniform vec2 pixel;    // grid step, mm
flat out vec2 depth_range;
flat out vec4 f_ref;
flat out vec3 f_plane;
flat out vec2 f_q0;
flat out vec4 f_src;
flat out float f_reach2;
void main() {
  vec3 p = pos + offset;
  gl_ClipDistance[0] = dot(plane0, vec3(p.xy, 1.0));
  gl_ClipDistance[1] = dot(plane1, vec3(p.xy, 1.0));
  gl_ClipDistance[2] = dot(plane2, vec3(p.xy, 1.0));
  gl_Position = vec4(p.xy * xy_map.xy + xy_map.zw, p.z * z_map, 1.0);
  depth_range = (zrange + offset.z) * (0.5 * z_map) + 0.5;
  f_ref = ref;
  f_plane = vec3((plane.x + offset.z) * (0.5 * z_map), plane.y * pixel.x * (0.5 * z_map), plane.z * pixel.y * (0.5 * z_map));
  f_q0 = q0 / pixel;
  f_src = src;
  f_reach2 = reach2;
}
)";
// The depth of a fragment is its triangle's plane evaluated at the pixel
// centre (the node) from the unsnapped triangle: a rasterizer snaps vertices
// to a sub-pixel grid (1/256 pixel in llvmpipe), which on a steep triangle
// would move its interpolated depth by slope * snap. Clamped to the
// triangle's own z range: a pixel lit just outside a steep, thin triangle
// must not take its plane far beyond it.
// A node farther in XY than the cutter's reach from the primitive whose
// offset the triangle belongs to (a vertex, an edge, a facet: the source,
// with ref its first corner) is out of that primitive's reach whatever the
// rasterizer's snapping lit: discarded.
const char* const kFragmentShader = R"(#version 330 core
flat in vec2 depth_range;
flat in vec4 f_ref;
flat in vec3 f_plane;
flat in vec2 f_q0;
flat in vec4 f_src;
flat in float f_reach2;
uniform vec2 pixel;
float segment_dist2(vec2 p, vec2 a, vec2 b) {
  vec2 ab = b - a;
  float l2 = dot(ab, ab);
  float t = l2 > 0.0 ? clamp(dot(p - a, ab) / l2, 0.0, 1.0) : 0.0;
  vec2 q = (p - a) - t * ab;
  return dot(q, q);
}
float cross2(vec2 a, vec2 b) { return a.x * b.y - a.y * b.x; }
// Squared distance from p to the triangle (0, s1, s2), which may be a
// segment (s2 = s1) or a point (both 0).
float source_dist2(vec2 p, vec2 s1, vec2 s2) {
  if (s1 == vec2(0.0) && s2 == vec2(0.0)) return dot(p, p);
  float area = cross2(s1, s2);
  if (area != 0.0) {
    float c1 = cross2(s1, p) * area, c2 = cross2(s2 - s1, p - s1) * area, c3 = cross2(-s2, p - s2) * area;
    if (c1 >= 0.0 && c2 >= 0.0 && c3 >= 0.0) return 0.0;
  }
  return min(segment_dist2(p, vec2(0.0), s1), min(segment_dist2(p, s1, s2), segment_dist2(p, s2, vec2(0.0))));
}
void main() {
  vec2 rel = (gl_FragCoord.xy - f_ref.xy) - f_ref.zw;  // pixels from the source's first corner
  if (source_dist2(rel * pixel, f_src.xy, f_src.zw) > f_reach2) discard;
  vec2 d = rel - f_q0;
  float depth = (f_plane.x + 0.5) + f_plane.y * d.x + f_plane.z * d.y;
  gl_FragDepth = clamp(depth, depth_range.x, depth_range.y);
}
)";

// Window coordinates of the current tile, in double: pixel centres at +0.5.
struct TileMap {
  double x0 = 0, y0 = 0, dx = 1, dy = 1;  // grid origin and step
  double ti = 0, tj = 0;                  // tile's first node
  double wx(double x) const { return (x - x0) / dx - ti + 0.5; }
  double wy(double y) const { return (y - y0) / dy - tj + 0.5; }
};

// A double as float hi + lo (hi + lo == v to about 1e-14 relative).
void split(double v, float& hi, float& lo) {
  hi = static_cast<float>(v);
  lo = static_cast<float>(v - static_cast<double>(hi));
}

// Plane z = z0 + gx * (x - x_0) + gy * (y - y_0) through three points; false
// when the triangle has no area seen from above.
bool plane_of(const geometry::Vec3& a, const geometry::Vec3& b, const geometry::Vec3& c, double& gx, double& gy) {
  const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z, vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
  const double det = ux * vy - uy * vx;
  if (det == 0) return false;
  gx = (uz * vy - uy * vz) / det;
  gy = (ux * vz - uz * vx) / det;
  return true;
}

// ---------------------------------------------------------------- geometry

// xy half-planes a*x + b*y + c >= 0 (relative coordinates); all-pass by default.
struct Planes {
  float p[9] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
};

// The vertical prism of a facet as three inward half-planes; false where the
// facet's xy triangle has no area (a vertical facet: its prism is empty).
bool prism_planes(const geometry::Vec3& a, const geometry::Vec3& b, const geometry::Vec3& c, Planes& out) {
  const double area2 = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
  const double scale = std::max({norm(b - a), norm(c - a), norm(c - b)});
  if (!(std::fabs(area2) > 1e-12 * scale * scale)) return false;
  const geometry::Vec3 v[3] = {a, b, c};
  const double sgn = area2 > 0 ? 1.0 : -1.0;
  for (std::size_t k = 0; k < 3; ++k) {
    const geometry::Vec3& p = v[k];
    const geometry::Vec3& q = v[(k + 1) % 3];
    double nx = -(q.y - p.y) * sgn, ny = (q.x - p.x) * sgn;
    const double len = std::hypot(nx, ny);
    nx /= len;
    ny /= len;
    out.p[3 * k] = static_cast<float>(nx);
    out.p[3 * k + 1] = static_cast<float>(ny);
    out.p[3 * k + 2] = static_cast<float>(-(nx * p.x + ny * p.y));
  }
  return true;
}

// The mesh primitive a drawn triangle belongs to, in XY: a vertex, an edge
// or a facet (ref and up to two more corners, relative), and the squared
// reach within which a node may take its height from it: the cutter's
// radius less a margin for float rounding in the shader (relative 2^-24 per
// step, on offsets up to the primitive's size plus R), so that a node that
// is just out of reach is never lit by it (the depth buffer's triangles are
// inscribed in XY as well as in Z).
struct Source {
  geometry::Vec3 ref;
  float s[4] = {0, 0, 0, 0};
  float reach2 = 0;
};

Source make_source(const geometry::Vec3& p0, const geometry::Vec3* p1, const geometry::Vec3* p2, double R) {
  Source s;
  s.ref = p0;
  double size = 0;
  const geometry::Vec3* corners[2] = {p1 ? p1 : &p0, p2 ? p2 : (p1 ? p1 : &p0)};
  for (int k = 0; k < 2; ++k) {
    const double x = corners[k]->x - p0.x, y = corners[k]->y - p0.y;
    s.s[2 * k] = static_cast<float>(x);
    s.s[2 * k + 1] = static_cast<float>(y);
    size = std::max(size, std::hypot(x, y));
  }
  const double reach = std::max(0.0, R - std::ldexp(R + size, -18));
  s.reach2 = static_cast<float>(reach * reach);
  return s;
}

struct Setup {
  const geometry::Mesh& mesh;
  geometry::Vec3 origin;  // relative coordinates: x - origin.x etc. (origin.z: middle of the depth range)
  bool trim;
};

// Triangles streamed to the GPU in bounded batches (the edge sweeps of a
// large mesh would not fit in memory at once).
class Batch {
 public:
  Batch(bool with_planes) : planes_(with_planes) {
    glGenVertexArrays(1, &vao_);
    glGenBuffers(1, &vbo_);
    data_.reserve(kMaxVertices * stride());
  }
  ~Batch() {
    glDeleteBuffers(1, &vbo_);
    glDeleteVertexArrays(1, &vao_);
  }
  Batch(const Batch&) = delete;
  Batch& operator=(const Batch&) = delete;

  void triangle(const geometry::Vec3& a, const geometry::Vec3& b, const geometry::Vec3& c, const geometry::Vec3& o, const TileMap& tm, const Planes* pl,
                const Source& src) {
    // A triangle with no area seen from above (a vertical one) adds nothing
    // to the top view, and its depth plane is meaningless in float: a
    // rasterizer may still light a pixel with it. Leave such ones out.
    const double ux = b.x - a.x, uy = b.y - a.y, vx = c.x - a.x, vy = c.y - a.y;
    const double area2 = std::fabs(ux * vy - uy * vx), size2 = ux * ux + uy * uy + vx * vx + vy * vy;
    if (!(area2 > 1e-6 * size2)) return;
    double gx = 0, gy = 0;
    if (!plane_of(a, b, c, gx, gy)) return;
    if (data_.size() + 3 * stride() > kMaxVertices * stride()) flush();
    const float zlo = static_cast<float>(std::min({a.z, b.z, c.z}) - o.z);
    const float zhi = static_cast<float>(std::max({a.z, b.z, c.z}) - o.z);
    // ref: the source's first corner; the plane holds at a (q0 from ref).
    float rx, rxl, ry, ryl;
    split(tm.wx(src.ref.x), rx, rxl);
    split(tm.wy(src.ref.y), ry, ryl);
    const float z0 = static_cast<float>(a.z - o.z);
    const auto q0x = static_cast<float>(a.x - src.ref.x), q0y = static_cast<float>(a.y - src.ref.y);
    for (const geometry::Vec3* v : {&a, &b, &c}) {
      data_.insert(data_.end(), {static_cast<float>(v->x - o.x), static_cast<float>(v->y - o.y),
                                 static_cast<float>(v->z - o.z), zlo, zhi, rx, ry, rxl, ryl, z0,
                                 static_cast<float>(gx), static_cast<float>(gy), q0x, q0y, src.s[0], src.s[1],
                                 src.s[2], src.s[3], src.reach2});
      if (planes_) {
        const Planes def;
        const Planes& p = pl ? *pl : def;
        data_.insert(data_.end(), p.p, p.p + 9);
      }
    }
    ++triangles_;
  }
  void flush() {
    if (data_.empty()) return;
    glBindVertexArray(vao_);
    glBindBuffer(GL_ARRAY_BUFFER, vbo_);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(data_.size() * sizeof(float)), data_.data(), GL_STREAM_DRAW);
    const auto st = static_cast<GLsizei>(stride() * sizeof(float));
    // Attribute `loc`: n floats at `floats` into each vertex.
    auto attrib = [st](GLuint loc, GLint n, std::size_t floats) {
      glEnableVertexAttribArray(loc);
      glVertexAttribPointer(loc, n, GL_FLOAT, GL_FALSE, st, buffer_offset(floats));
    };
    attrib(0, 3, 0);    // pos
    attrib(5, 2, 3);    // zrange
    attrib(6, 4, 5);    // ref
    attrib(7, 3, 9);    // plane
    attrib(8, 2, 12);   // q0
    attrib(9, 4, 14);   // src
    attrib(10, 1, 18);  // reach2
    glDisableVertexAttribArray(1);
    glVertexAttrib3f(1, 0, 0, 0);
    for (GLuint k = 0; k < 3; ++k) {
      if (planes_) {
        attrib(2 + k, 3, 19 + 3 * k);
      } else {
        glDisableVertexAttribArray(2 + k);
        glVertexAttrib3f(2 + k, 0, 0, 1);
      }
    }
    glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(data_.size() / stride()));
    data_.clear();
  }
  std::size_t triangles() const { return triangles_; }

 private:
  static constexpr std::size_t kMaxVertices = 3 << 16;
  std::size_t stride() const { return planes_ ? 28 : 19; }
  bool planes_;
  GLuint vao_ = 0, vbo_ = 0;
  std::vector<float> data_;
  std::size_t triangles_ = 0;
};

// Vertex offsets: the cap drawn once per instance (a vertex, and in trim mode
// the prism of the facet it is drawn for).
class CapDraw {
 public:
  // reach2: the vertex's squared reach (make_source).
  CapDraw(const CutterCap& cap, bool with_planes, float reach2) : planes_(with_planes), reach2_(reach2) {
    std::vector<float> tris;
    const auto& P = cap.points();
    for (const auto& t : cap.triangles()) {
      const geometry::Vec3 a = P[t[0]], b = P[t[1]], c = P[t[2]];
      double gx = 0, gy = 0;
      plane_of(a, b, c, gx, gy);
      const double zlo = std::min({a.z, b.z, c.z}), zhi = std::max({a.z, b.z, c.z});
      for (const geometry::Vec3* v : {&a, &b, &c})
        tris.insert(tris.end(), {static_cast<float>(v->x), static_cast<float>(v->y), static_cast<float>(v->z),
                                 static_cast<float>(zlo), static_cast<float>(zhi), static_cast<float>(a.z),
                                 static_cast<float>(gx), static_cast<float>(gy), static_cast<float>(a.x),
                                 static_cast<float>(a.y)});
    }
    vertices_ = static_cast<GLsizei>(tris.size() / 10);
    glGenVertexArrays(1, &vao_);
    glGenBuffers(1, &mesh_vbo_);
    glGenBuffers(1, &inst_vbo_);
    glBindVertexArray(vao_);
    glBindBuffer(GL_ARRAY_BUFFER, mesh_vbo_);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(tris.size() * sizeof(float)), tris.data(), GL_STATIC_DRAW);
    const GLsizei st = 10 * sizeof(float);
    auto at = [](std::size_t floats) { return buffer_offset(floats); };
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, st, at(0));
    glEnableVertexAttribArray(5);
    glVertexAttribPointer(5, 2, GL_FLOAT, GL_FALSE, st, at(3));
    glEnableVertexAttribArray(7);
    glVertexAttribPointer(7, 3, GL_FLOAT, GL_FALSE, st, at(5));
    glEnableVertexAttribArray(8);
    glVertexAttribPointer(8, 2, GL_FLOAT, GL_FALSE, st, at(8));
  }
  ~CapDraw() {
    glDeleteBuffers(1, &inst_vbo_);
    glDeleteBuffers(1, &mesh_vbo_);
    glDeleteVertexArrays(1, &vao_);
  }
  CapDraw(const CapDraw&) = delete;
  CapDraw& operator=(const CapDraw&) = delete;

  void add(const geometry::Vec3& v, const geometry::Vec3& o, const TileMap& tm, const Planes* pl) {
    float rx, rxl, ry, ryl;
    split(tm.wx(v.x), rx, rxl);
    split(tm.wy(v.y), ry, ryl);
    inst_.insert(inst_.end(), {static_cast<float>(v.x - o.x), static_cast<float>(v.y - o.y),
                               static_cast<float>(v.z - o.z), rx, ry, rxl, ryl});
    if (planes_) {
      const Planes def;
      const Planes& p = pl ? *pl : def;
      inst_.insert(inst_.end(), p.p, p.p + 9);
    }
  }
  std::size_t instances() const { return inst_.size() / stride(); }
  void draw() {
    if (inst_.empty()) return;
    glBindVertexArray(vao_);
    glBindBuffer(GL_ARRAY_BUFFER, inst_vbo_);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(inst_.size() * sizeof(float)), inst_.data(), GL_STREAM_DRAW);
    // The source is the vertex itself (ref): no other corners.
    glDisableVertexAttribArray(9);
    glVertexAttrib4f(9, 0, 0, 0, 0);
    glDisableVertexAttribArray(10);
    glVertexAttrib1f(10, reach2_);
    const auto st = static_cast<GLsizei>(stride() * sizeof(float));
    // Instances in chunks: llvmpipe bins a whole draw before rasterizing it.
    const std::size_t n = instances(), chunk = 4096;
    for (std::size_t first = 0; first < n; first += chunk) {
      auto at = [&](std::size_t floats) { return buffer_offset(first * stride() + floats); };
      glEnableVertexAttribArray(1);
      glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, st, at(0));
      glVertexAttribDivisor(1, 1);
      glEnableVertexAttribArray(6);
      glVertexAttribPointer(6, 4, GL_FLOAT, GL_FALSE, st, at(3));
      glVertexAttribDivisor(6, 1);
      for (GLuint k = 0; k < 3; ++k) {
        if (planes_) {
          glEnableVertexAttribArray(2 + k);
          glVertexAttribPointer(2 + k, 3, GL_FLOAT, GL_FALSE, st, at(7 + 3 * k));
          glVertexAttribDivisor(2 + k, 1);
        } else {
          glDisableVertexAttribArray(2 + k);
          glVertexAttrib3f(2 + k, 0, 0, 1);
        }
      }
      glDrawArraysInstanced(GL_TRIANGLES, 0, vertices_, static_cast<GLsizei>(std::min(chunk, n - first)));
    }
    inst_.clear();
  }
  std::size_t triangles_per_instance() const { return static_cast<std::size_t>(vertices_) / 3; }

 private:
  std::size_t stride() const { return planes_ ? 16 : 7; }
  bool planes_;
  float reach2_;
  GLuint vao_ = 0, mesh_vbo_ = 0, inst_vbo_ = 0;
  GLsizei vertices_ = 0;
  std::vector<float> inst_;
};

// Manifold edges between two coplanar non-steep facets: their face offsets
// are moved by the same vector, so they share the offset edge exactly and
// the rasterizer covers every node along it. (The exact engine also leaves
// out valley edges; there the two face offsets meet along different lines,
// and a node in the crack between them, which the exact engine's inclusion
// tolerance catches, would fall through to what lies below.)
struct EdgeSlot {
  std::uint32_t a = 0, b = 0;
  std::uint32_t opposite[2] = {0, 0};
  std::uint32_t count = 0;
};

bool redundant(const geometry::Mesh& m, const EdgeSlot& s) {
  if (s.count != 2) return false;
  const geometry::Vec3 pa = m.vertices[s.a], pb = m.vertices[s.b];
  const geometry::Vec3 oa = m.vertices[s.opposite[0]], ob = m.vertices[s.opposite[1]];
  const geometry::Vec3 na = upward_unit_normal(pa, pb, oa), nb = upward_unit_normal(pa, pb, ob);
  if (na.z < 0.01 || nb.z < 0.01) return false;
  if (norm(na - nb) > 1e-9) return false;
  const bool ha = std::hypot(na.x, na.y) < 1e-9, hb = std::hypot(nb.x, nb.y) < 1e-9;
  if (ha != hb) return false;
  const double ex = pb.x - pa.x, ey = pb.y - pa.y;
  const double side_a = ex * (oa.y - pa.y) - ey * (oa.x - pa.x);
  const double side_b = ex * (ob.y - pa.y) - ey * (ob.x - pa.x);
  if (!(side_a * side_b < 0)) return false;
  return dot(ob - pa, na) >= 0 && dot(oa - pa, nb) >= 0;
}

std::vector<EdgeSlot> mesh_edges(const geometry::Mesh& m) {
  std::unordered_map<std::uint64_t, std::uint32_t> index;
  index.reserve(m.triangles.size() * 2);
  std::vector<EdgeSlot> out;
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k) {
      std::uint32_t a = t[k], b = t[(k + 1) % 3];
      if (a == b) continue;
      if (a > b) std::swap(a, b);
      const std::uint64_t key = (std::uint64_t{a} << 32) | b;
      auto [it, fresh] = index.try_emplace(key, static_cast<std::uint32_t>(out.size()));
      if (fresh) out.push_back({a, b, {0, 0}, 0});
      EdgeSlot& s = out[it->second];
      if (s.count < 2) s.opposite[s.count] = t[(k + 2) % 3];
      ++s.count;
    }
  return out;
}

// ---------------------------------------------------------------- framebuffer

class DepthTarget {
 public:
  DepthTarget(GLsizei w, GLsizei h) {
    glGenFramebuffers(1, &fbo_);
    glGenRenderbuffers(1, &rb_);
    glBindRenderbuffer(GL_RENDERBUFFER, rb_);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb_);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    const GLenum st = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    if (st != GL_FRAMEBUFFER_COMPLETE) {
      throw GlError(fmt::format("OpenGL: the {}x{} float depth framebuffer is incomplete (status 0x{:04X})", w, h, st));
    }
  }
  ~DepthTarget() {
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteRenderbuffers(1, &rb_);
    glDeleteFramebuffers(1, &fbo_);
  }
  DepthTarget(const DepthTarget&) = delete;
  DepthTarget& operator=(const DepthTarget&) = delete;

 private:
  GLuint fbo_ = 0, rb_ = 0;
};

void check_spec(const cam::GridSpec& s) {
  if (!(s.dx > 0) || !(s.dy > 0) || !std::isfinite(s.dx) || !std::isfinite(s.dy))
    throw std::invalid_argument("GL CL engine: grid step must be positive and finite");
  if (!std::isfinite(s.x0) || !std::isfinite(s.y0)) throw std::invalid_argument("GL CL engine: grid origin must be finite");
}

}  // namespace

cam::ClGrid compute_cl_grid_gl(const geometry::Mesh& mesh, const cam::Cutter& cutter, const cam::GridSpec& spec, const GlClOptions& opt,
                          GlClStats* stats_out) {
  check_spec(spec);
  if (opt.floor && !std::isfinite(*opt.floor)) throw std::invalid_argument("GL CL engine: floor must be finite");
  const CutterCap cap(cutter, opt.tolerance);
  const geometry::Box3 box = mesh.bounds();
  cam::ClGrid grid;
  grid.spec = spec;
  grid.floor = opt.floor ? *opt.floor : (box.empty() ? 0.0 : box.lo.z);
  grid.z.assign(spec.size(), grid.floor);
  grid.on_floor.assign(spec.size(), 1);

  GlClStats st;
  st.cap_spokes = cap.spokes();
  st.cap_rings = cap.ring_radius().size();
  st.sliver_width = cap.sliver_width();
  st.height_error_bound = cap.height_error_bound();

  // One grid at a time per process: EGL's surfaceless display is one per
  // process, and each call initializes and terminates it.
  static std::mutex one_at_a_time;
  const std::lock_guard<std::mutex> lock(one_at_a_time);
  const EglContext ctx(opt.egl_platform);
  st.renderer = ctx.renderer();
  if (spec.size() == 0 || box.empty()) {
    if (stats_out) *stats_out = st;
    return grid;
  }

  // Depth range tight to what can be drawn: from the lowest vertex minus the
  // corner radius (a rim point) to the highest vertex, plus a margin so that
  // every drawn height has a depth above the cleared 0.
  const double rk = !cutter.is_apt()                   ? cutter.profile_top()
                    : cutter.type == cam::CutterType::Flat ? 0.0
                    : cutter.type == cam::CutterType::Ball ? cutter.radius
                                                      : cutter.corner_radius;
  const double span0 = box.hi.z - (box.lo.z - rk);
  const double margin = 1e-3 * std::max(1.0, span0);
  const double zlo = box.lo.z - rk - margin, zhi = box.hi.z + margin;
  const geometry::Vec3 origin{spec.x0, spec.y0, 0.5 * (zlo + zhi)};
  st.depth_quantum = (zhi - zlo) * std::ldexp(1.0, -24);

  GLint max_rb = 0, vp[2] = {0, 0};
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_rb);
  glGetIntegerv(GL_MAX_VIEWPORT_DIMS, vp);
  std::size_t tile = std::min<std::size_t>({4096, static_cast<std::size_t>(std::max(1, max_rb)),
                                            static_cast<std::size_t>(std::max(1, std::min(vp[0], vp[1])))});
  if (opt.max_tile) tile = std::min(tile, opt.max_tile);
  const std::size_t tw = std::min(tile, spec.nx), th = std::min(tile, spec.ny);

  const GLuint program = link_shader_program(kVertexShader, kFragmentShader, "depth");
  glUseProgram(program);
  const GLint loc_xy = glGetUniformLocation(program, "xy_map"), loc_z = glGetUniformLocation(program, "z_map");
  glUniform1f(loc_z, static_cast<float>(2.0 / (zhi - zlo)));
  glUniform2f(glGetUniformLocation(program, "pixel"), static_cast<float>(spec.dx), static_cast<float>(spec.dy));
  const DepthTarget target(static_cast<GLsizei>(tw), static_cast<GLsizei>(th));
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_GREATER);
  glClearDepth(0.0);
  glDisable(GL_CULL_FACE);
  if (opt.trim)
    for (int k = 0; k < 3; ++k) glEnable(GL_CLIP_DISTANCE0 + k);

  // What is drawn, decided once.
  std::vector<std::array<geometry::Vec3, 3>> faces;
  std::vector<Source> face_sources;  // the facets themselves
  for (const auto& t : mesh.triangles) {
    std::array<geometry::Vec3, 3> f;
    const geometry::Vec3 &p0 = mesh.vertices[t[0]], &p1 = mesh.vertices[t[1]], &p2 = mesh.vertices[t[2]];
    if (face_offset_triangle(p0, p1, p2, cutter, f)) {
      faces.push_back(f);
      face_sources.push_back(make_source(p0, &p1, &p2, cutter.radius));
    }
  }
  st.face_offsets = faces.size();
  struct EdgeDraw {
    std::uint32_t a, b;
    Planes planes;
  };
  struct VertexDraw {
    std::uint32_t v;
    Planes planes;
  };
  std::vector<EdgeDraw> edges;
  std::vector<VertexDraw> verts;
  if (opt.trim) {
    // The thesis: each facet draws its own three edges and three vertices,
    // clipped to its vertical prism (its bounding space).
    for (const auto& t : mesh.triangles) {
      Planes pl;
      if (!prism_planes(mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]], pl)) continue;
      for (int k = 0; k < 3; ++k) {
        edges.push_back({t[k], t[(k + 1) % 3], pl});
        verts.push_back({t[k], pl});
      }
    }
  } else {
    std::vector<std::uint8_t> used(mesh.vertices.size(), 0);
    for (const auto& t : mesh.triangles)
      for (auto i : t) used[i] = 1;
    for (const EdgeSlot& s : mesh_edges(mesh))
      if (!opt.skip_coplanar_edges || !redundant(mesh, s)) edges.push_back({s.a, s.b, {}});
    for (std::uint32_t v = 0; v < used.size(); ++v)
      if (used[v]) verts.push_back({v, {}});
  }
  st.edges_drawn = edges.size();
  st.vertices_drawn = verts.size();

  // Each edge's generators on the exact offset surface, once for all tiles.
  std::vector<geometry::Vec3> gens, one;
  std::vector<std::size_t> gen_first{0};
  gen_first.reserve(edges.size() + 1);
  for (const EdgeDraw& e : edges) {
    edge_generators(cutter, mesh.vertices[e.a], mesh.vertices[e.b], opt.tolerance, one);
    gens.insert(gens.end(), one.begin(), one.end());
    gen_first.push_back(gens.size());
  }

  Batch batch(opt.trim);
  CapDraw caps(cap, opt.trim, make_source(geometry::Vec3{}, nullptr, nullptr, cutter.radius).reach2);
  // The radius of the circle inside the cap's rim polygon (a hair less).
  const double r_in = cutter.radius * std::cos(M_PI / static_cast<double>(cap.spokes())) * (1 - 1e-7);
  std::vector<float> depth(tw * th);
  const double R = cutter.radius;
  for (std::size_t tj = 0; tj < spec.ny; tj += th)
    for (std::size_t ti = 0; ti < spec.nx; ti += tw) {
      const std::size_t w = std::min(tw, spec.nx - ti), h = std::min(th, spec.ny - tj);
      ++st.tiles;
      glViewport(0, 0, static_cast<GLsizei>(w), static_cast<GLsizei>(h));
      glUniform4f(loc_xy, static_cast<float>(2.0 / (static_cast<double>(w) * spec.dx)),
                  static_cast<float>(2.0 / (static_cast<double>(h) * spec.dy)),
                  static_cast<float>((0.5 - static_cast<double>(ti)) * 2.0 / static_cast<double>(w) - 1.0),
                  static_cast<float>((0.5 - static_cast<double>(tj)) * 2.0 / static_cast<double>(h) - 1.0));
      glClear(GL_DEPTH_BUFFER_BIT);
      TileMap tm;
      tm.x0 = spec.x0;
      tm.y0 = spec.y0;
      tm.dx = spec.dx;
      tm.dy = spec.dy;
      tm.ti = static_cast<double>(ti);
      tm.tj = static_cast<double>(tj);
      // The tile's xy range, grown by a pixel: what lies wholly outside is skipped.
      const double x0 = spec.x(ti) - spec.dx, x1 = spec.x(ti + w - 1) + spec.dx;
      const double y0 = spec.y(tj) - spec.dy, y1 = spec.y(tj + h - 1) + spec.dy;
      auto outside = [&](double lx, double ly, double hx, double hy) { return hx < x0 || lx > x1 || hy < y0 || ly > y1; };

      for (std::size_t k = 0; k < faces.size(); ++k) {
        const auto& f = faces[k];
        const double lx = std::min({f[0].x, f[1].x, f[2].x}), hx = std::max({f[0].x, f[1].x, f[2].x});
        const double ly = std::min({f[0].y, f[1].y, f[2].y}), hy = std::max({f[0].y, f[1].y, f[2].y});
        if (!outside(lx, ly, hx, hy)) batch.triangle(f[0], f[1], f[2], origin, tm, nullptr, face_sources[k]);
      }
      for (const VertexDraw& vd : verts) {
        const geometry::Vec3& v = mesh.vertices[vd.v];
        if (!outside(v.x - R, v.y - R, v.x + R, v.y + R)) caps.add(v, origin, tm, opt.trim ? &vd.planes : nullptr);
      }
      st.triangles += caps.instances() * caps.triangles_per_instance();
      caps.draw();
      for (std::size_t k = 0; k < edges.size(); ++k) {
        const EdgeDraw& e = edges[k];
        const geometry::Vec3 a = mesh.vertices[e.a], b = mesh.vertices[e.b];
        if (outside(std::min(a.x, b.x) - R, std::min(a.y, b.y) - R, std::max(a.x, b.x) + R, std::max(a.y, b.y) + R)) continue;
        const Planes* pl = opt.trim ? &e.planes : nullptr;
        const Source segment = make_source(a, &b, nullptr, R);
        // The uphill end's generators start on the exact rim of its vertex
        // offset, whose drawn polygon is inscribed: an apron, flat at the
        // lower of the two generators' heights, reaches back from them into
        // the polygon (inside the disc, where the vertex offset is at least
        // that high), so no lens between polygon and rim is left uncovered.
        const double L = std::hypot(b.x - a.x, b.y - a.y);
        const double m = L > 0 ? (b.z - a.z) / L : 0.0;
        const geometry::Vec3 up = m < 0 ? a : b;
        const geometry::Vec3 dir = L > 0 ? geometry::Vec3{(b.x - a.x) / L, (b.y - a.y) / L, 0} * (m < 0 ? -1.0 : 1.0) : geometry::Vec3{};
        auto apron = [&](const geometry::Vec3& q, double& delta) {  // false: the generator cannot reach inside
          const double sdot = -(q.x * dir.x + q.y * dir.y), c2 = q.x * q.x + q.y * q.y - r_in * r_in;
          if (c2 <= 0) return delta = 0, true;
          if (sdot * sdot < c2) return false;
          delta = sdot - std::sqrt(sdot * sdot - c2) + 1e-6 * R;
          return true;
        };
        for (std::size_t g = gen_first[k]; g + 1 < gen_first[k + 1]; ++g) {
          const geometry::Vec3 q1 = gens[g], q2 = gens[g + 1];
          batch.triangle(a + q1, a + q2, b + q2, origin, tm, pl, segment);
          batch.triangle(a + q1, b + q2, b + q1, origin, tm, pl, segment);
          double d1 = 0, d2 = 0;
          if (m != 0 && apron(q1, d1) && apron(q2, d2) && (d1 > 0 || d2 > 0)) {
            const double z = up.z + std::min(q1.z, q2.z);
            const geometry::Vec3 p1{up.x + q1.x, up.y + q1.y, z}, p2{up.x + q2.x, up.y + q2.y, z};
            const geometry::Vec3 p3 = p2 + dir * d2, p4 = p1 + dir * d1;
            const Source vertex = make_source(up, nullptr, nullptr, R);
            batch.triangle(p1, p2, p3, origin, tm, pl, vertex);
            batch.triangle(p1, p3, p4, origin, tm, pl, vertex);
          }
        }
      }
      batch.flush();
      glPixelStorei(GL_PACK_ALIGNMENT, 1);
      glReadPixels(0, 0, static_cast<GLsizei>(w), static_cast<GLsizei>(h), GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
      if (const GLenum err = glGetError(); err != GL_NO_ERROR) {
        throw GlError(fmt::format("OpenGL: rendering the depth tile failed (GL error 0x{:04X})", err));
      }
      for (std::size_t r = 0; r < h; ++r)
        for (std::size_t c = 0; c < w; ++c) {
          const float d = depth[r * w + c];
          if (!(d > 0)) continue;
          const std::size_t k = (tj + r) * spec.nx + ti + c;
          grid.z[k] = zlo + static_cast<double>(d) * (zhi - zlo);
          grid.on_floor[k] = 0;
        }
    }
  st.triangles += batch.triangles();
  glDeleteProgram(program);
  if (opt.lift_to_bound) {
    st.lifted = st.height_error_bound + 2 * st.depth_quantum;
    for (std::size_t k = 0; k < grid.z.size(); ++k)
      if (!grid.on_floor[k]) grid.z[k] += st.lifted;
  }
  if (stats_out) *stats_out = st;
  return grid;
}

}  // namespace cncstream::gl
