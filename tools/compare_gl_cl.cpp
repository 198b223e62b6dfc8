// The thesis's depth-buffer CL engine (GL) against the exact CPU engine, node
// by node: largest error above and below, the error against the tessellation
// tolerance, how many nodes the trimmed variant (bounding spaces) puts below
// the exact surface by more than the tolerance, and the time of each engine.
// Prints a Markdown table.
//
//   compare_gl_cl [--grid STEP] [--tol 0.1,0.03,0.01] [--tools flat:6,ball:6,bull:6:1]
//                 [--no-trim] [--threads N] MESH.stl[@SCALE] ...
//
// MESH@SCALE multiplies the mesh's coordinates (the shared meshes are partly
// unit-less); a mesh with an XY extent under 10 units is otherwise scaled to
// 100 mm across.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/cam/raster.hpp"
#include "cncstream/geometry/stl.hpp"
#include "cncstream/gl/boundary_nodes.hpp"
#include "cncstream/gl/gl_cl_engine.hpp"

using namespace cncstream;

namespace {

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string part; std::getline(ss, part, sep);)
    if (!part.empty()) out.push_back(part);
  return out;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct Errors {
  double above = 0, below = 0;  // largest gl - exact > 0, exact - gl > 0, boundary nodes left out
  std::size_t below_tol = 0;    // nodes with gl < exact - tol - eps, boundary nodes left out
  std::size_t boundary = 0;     // nodes off by more, within `reach` of a vertical part of the exact surface
  std::size_t worst_above = 0, worst_below = 0;
};

// Node by node. A node above by more than eps that the exact surface reaches
// within the rasterizer's snap distance, or below by more than tol + eps
// that the exact surface drops to within the cap's sliver width, is a
// boundary node (beside a vertical part of the exact surface): counted, not
// in the maxima. With `classify` false every node counts (the trimmed runs).
Errors compare(const cam::ClEngine& engine, const cam::ClGrid& exact, const cam::ClGrid& g, double tol, double eps, double snap,
               double sliver, bool classify) {
  Errors e;
  const cam::GridSpec& s = exact.spec;
  for (std::size_t k = 0; k < exact.z.size(); ++k) {
    const double d = g.z[k] - exact.z[k];
    const double x = s.x(k % s.nx), y = s.y(k / s.nx);
    if (classify && d > eps && gl::exact_height_around(engine, x, y, snap, true) >= g.z[k] - eps) {
      ++e.boundary;
      continue;
    }
    if (classify && d < -tol - eps &&
        gl::exact_height_around(engine, x, y, 1.05 * sliver + snap, false) <= g.z[k] + tol + eps) {
      ++e.boundary;
      continue;
    }
    if (d > e.above) e.above = d, e.worst_above = k;
    if (-d > e.below) e.below = -d, e.worst_below = k;
    if (d < -tol - eps && ++e.below_tol <= 10 && std::getenv("COMPARE_GL_DEBUG"))
      std::fprintf(stderr, "  below: node (%zu, %zu) at (%.6f, %.6f): exact %.6f gl %.6f\n", k % s.nx, k / s.nx, x, y,
                   exact.z[k], g.z[k]);
  }
  return e;
}

}  // namespace

int main(int argc, char** argv) {
  double step = 0.5;
  std::vector<double> tols = {0.1, 0.03, 0.01};
  std::vector<std::string> tools = {"flat:6", "ball:6", "bull:6:1"};
  bool trim = true;
  unsigned threads = 0;
  std::vector<std::string> meshes;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << a << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--grid") step = std::stod(next());
    else if (a == "--tol") {
      tols.clear();
      for (const auto& t : split(next(), ',')) tols.push_back(std::stod(t));
    } else if (a == "--tools") tools = split(next(), ',');
    else if (a == "--no-trim") trim = false;
    else if (a == "--threads") threads = static_cast<unsigned>(std::stoul(next()));
    else if (a.rfind("--", 0) == 0) {
      std::cerr << "unknown option " << a << "\n";
      return 2;
    } else meshes.push_back(a);
  }
  if (meshes.empty()) {
    std::cerr << "usage: compare_gl_cl [--grid STEP] [--tol a,b] [--tools flat:6,ball:6] [--no-trim] MESH.stl[@SCALE] ...\n";
    return 2;
  }

  std::printf("| mesh | facets | tool | grid | exact s | tol mm | GL s | GL triangles | max above mm | max below mm | nodes below exact−tol | boundary nodes | trimmed GL s | trimmed max below mm | trimmed nodes below exact−tol |\n");
  std::printf("|---|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const std::string& arg : meshes) {
    std::string path = arg;
    double scale = 0;
    if (const auto at = arg.rfind('@'); at != std::string::npos) {
      path = arg.substr(0, at);
      scale = std::stod(arg.substr(at + 1));
    }
    geometry::Mesh mesh = geometry::load_stl(path).mesh;
    const geometry::Box3 b0 = mesh.bounds();
    if (scale == 0) scale = std::max(b0.size().x, b0.size().y) < 10 ? 100 / std::max(b0.size().x, b0.size().y) : 1;
    if (scale != 1) mesh.scale(scale);
    std::string name = path.substr(path.find_last_of('/') + 1);
    if (scale != 1) {
      char buf[32];
      std::snprintf(buf, sizeof buf, " ×%.4g", scale);
      name.append(buf);
    }
    for (const std::string& tool : tools) {
      const cam::Cutter cutter = cam::parse_cutter_spec(tool);
      const cam::XYBounds xb = cam::default_bounds(mesh, cutter);
      const cam::GridSpec spec = cam::GridSpec::covering(xb.x0, xb.y0, xb.x1, xb.y1, step, step);
      auto t0 = std::chrono::steady_clock::now();
      cam::ClOptions clo;
      clo.threads = threads;
      const cam::ClEngine engine(mesh, cutter, clo);
      const cam::ClGrid exact = engine.compute(spec);
      const double t_exact = seconds_since(t0);
      for (double tol : tols) {
        gl::GlClOptions o;
        o.tolerance = tol;
        o.floor = engine.floor();
        gl::GlClStats st;
        t0 = std::chrono::steady_clock::now();
        const cam::ClGrid g = gl::compute_cl_grid_gl(mesh, cutter, spec, o, &st);
        const double t_gl = seconds_since(t0);
        const double eps = 2e-3, snap = std::hypot(spec.dx, spec.dy) / 256;
        const Errors e = compare(engine, exact, g, tol, eps, snap, st.sliver_width, true);
        std::string trimmed = "| – | – | –";
        char tris[32];
        std::snprintf(tris, sizeof tris, "%.1f M", static_cast<double>(st.triangles) / 1e6);
        if (trim) {
          o.trim = true;
          t0 = std::chrono::steady_clock::now();
          const cam::ClGrid gt = gl::compute_cl_grid_gl(mesh, cutter, spec, o);
          const double t_trim = seconds_since(t0);
          const Errors et = compare(engine, exact, gt, tol, eps, snap, st.sliver_width, false);
          char buf[128];
          std::snprintf(buf, sizeof buf, "| %.2f | %.3f | %zu", t_trim, et.below, et.below_tol);
          trimmed = buf;
        }
        std::printf("| %s | %zu | %s | %zu × %zu @ %g | %.2f | %g | %.2f | %s | %.2g | %.3g | %zu | %zu %s |\n", name.c_str(),
                    mesh.size(), tool.c_str(), spec.nx, spec.ny, step, t_exact, tol, t_gl, tris, e.above, e.below,
                    e.below_tol, e.boundary, trimmed.c_str());
        std::fflush(stdout);
        if (std::getenv("COMPARE_GL_DEBUG")) {
          for (std::size_t k : {e.worst_above, e.worst_below})
            std::fprintf(stderr, "  node (%zu, %zu) at (%.6f, %.6f): exact %.6f gl %.6f\n", k % spec.nx, k / spec.nx,
                         spec.x(k % spec.nx), spec.y(k / spec.nx), exact.z[k], g.z[k]);
        }
        std::fprintf(stderr, "  %s %s tol %g: %zu spokes, %zu rings, %zu triangles, bound %.3g mm, sliver %.2g mm, %s\n",
                     name.c_str(), tool.c_str(), tol, st.cap_spokes, st.cap_rings, st.triangles, st.height_error_bound,
                     st.sliver_width, st.renderer.c_str());
      }
    }
  }
  return 0;
}
