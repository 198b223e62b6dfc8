// Viewer benchmark, headless (EGL surfaceless; llvmpipe without a GPU):
//   1. time to first frame for a program (default: the plaque's, made with
//      `cncstream toolpath examples/plaque.stl --tool ball:3.175 -o /tmp/plaque.nc`):
//      reading and interpreting the G-code, the context, the upload, the frame;
//   2. a synthetic program of N segments (default 5 million) as G-code text:
//      interpreting it into the line buffer and uploading it;
//   3. frame times with those N segments: the whole program from the iso and
//      top views, the timeline half-way, zoomed in to a tenth.
//
//   bench_viewer [--program FILE.nc] [--segments N] [--size WxH] [--frames K]
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cncstream/viewer/headless.hpp"

using namespace cncstream;
using namespace cncstream::viewer;

namespace {

double peak_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;
}

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

// A raster over 120 x 100 mm with a wavy Z, in rows of 2000 moves joined by
// a rapid lift, over and down: about `segments` moves, G-code text.
std::string synthetic_program(std::size_t segments) {
  const std::size_t per_row = 2000;
  const std::size_t rows = std::max<std::size_t>(1, segments / (per_row + 3));
  std::string g;
  g.reserve(segments * 24);
  g += "G21 G90 G17 G94\nG0 Z5\n";
  char line[96];
  for (std::size_t r = 0; r < rows; ++r) {
    const double y = 100.0 * static_cast<double>(r) / static_cast<double>(rows);
    std::snprintf(line, sizeof line, "G0 X0 Y%.4f\nG1 Z0 F500\n", y);
    g += line;
    for (std::size_t k = 1; k <= per_row; ++k) {
      const double x = 120.0 * static_cast<double>(k) / per_row;
      std::snprintf(line, sizeof line, "G1 X%.4f Z%.4f F2000\n", x, -2 + std::sin(x * 0.2) * std::cos(y * 0.15));
      g += line;
    }
    g += "G0 Z5\n";
  }
  return g;
}

std::string read_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(path + ": cannot open (make it with: cncstream toolpath examples/plaque.stl --tool ball:3.175 -o /tmp/plaque.nc)");
  std::ostringstream s;
  s << f.rdbuf();
  return std::move(s).str();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// K frames of the view; the median and the slowest, ms.
void frames(HeadlessView& hv, const Camera& cam, int k, const char* what) {
  std::vector<double> t;
  for (int i = 0; i < k; ++i) {
    const double t0 = now();
    hv.draw(cam);  // waits for the frame (glFinish)
    t.push_back((now() - t0) * 1e3);
  }
  std::printf("  frame %-28s median %8.1f ms, slowest %8.1f ms (%d frames)\n", what, median(t),
              *std::max_element(t.begin(), t.end()), k);
}

}  // namespace

int main(int argc, char** argv) {
  std::string program = "/tmp/plaque.nc";
  std::size_t segments = 5'000'000;
  int width = 1280, height = 800, k = 5;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--program")) program = argv[i + 1];
    else if (!std::strcmp(argv[i], "--segments")) segments = std::stoull(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--frames")) k = std::stoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--size")) {
      if (std::sscanf(argv[i + 1], "%dx%d", &width, &height) != 2) return std::fprintf(stderr, "--size WxH\n"), 2;
    } else {
      return std::fprintf(stderr, "usage: bench_viewer [--program FILE.nc] [--segments N] [--size WxH] [--frames K]\n"), 2;
    }
  }
  try {
    // 1. Time to first frame for a real program.
    {
      const double t0 = now();
      const std::string text = read_file(program);
      const double t_read = now();
      Scene s;
      s.program = build_toolpath(text);
      const double t_parse = now();
      HeadlessView hv(width, height);
      const double t_ctx = now();
      load_scene(hv.renderer(), s);
      const double t_up = now();
      hv.draw(camera_for(s, NamedView::Iso, width, height));
      const double t_frame = now();
      std::printf("first frame of %s (%zu lines, %zu segments, %zu arcs) at %dx%d on %s:\n", program.c_str(),
                  s.program->lines, s.program->size(), s.program->arcs, width, height, hv.gl_renderer().c_str());
      std::printf("  read %.3f s, interpret %.3f s, GL context %.3f s, upload %.3f s, frame %.3f s: total %.3f s\n",
                  t_read - t0, t_parse - t_read, t_ctx - t_parse, t_up - t_ctx, t_frame - t_up, t_frame - t0);
      frames(hv, camera_for(s, NamedView::Iso, width, height), k, "iso, whole program");
    }
    // 2. and 3. N segments.
    {
      const double t0 = now();
      const std::string text = synthetic_program(segments);
      const double t_gen = now();
      Scene s;
      s.program = build_toolpath(text);
      const double t_parse = now();
      std::optional<HeadlessView> view;  // one EGL display a process: one view at a time
      view.emplace(width, height);
      HeadlessView& hv = *view;
      const double t_ctx = now();
      load_scene(hv.renderer(), s);
      const double t_up = now();
      Camera iso = camera_for(s, NamedView::Iso, width, height);
      hv.draw(iso);
      const double t_frame = now();
      std::printf("synthetic program: %zu segments (%zu rapid), %.0f MB of G-code, %.0f MB line buffer:\n",
                  s.program->size(), s.program->rapids, text.size() / 1e6,
                  s.program->vertices.size() * sizeof(PathVertex) / 1e6);
      std::printf("  generate %.2f s; interpret %.2f s, GL context %.3f s, upload %.2f s, first frame %.2f s: "
                  "G-code to first frame %.2f s\n",
                  t_gen - t0, t_parse - t_gen, t_ctx - t_parse, t_up - t_ctx, t_frame - t_up, t_frame - t_gen);
      std::printf("  strip %zu vertices; at a distance %zu (tolerance %.4f mm, drawn from %.4f mm a pixel; iso: %.4f)\n",
                  hv.renderer().toolpath_vertices(), hv.renderer().toolpath_distant_vertices(),
                  hv.renderer().distant_tolerance(), 2 * hv.renderer().distant_tolerance(), iso.mm_per_pixel());
      frames(hv, iso, k, "iso, whole program");
      Camera top = camera_for(s, NamedView::Top, width, height);
      frames(hv, top, k, "top, whole program");
      hv.renderer().set_progress(*s.program, static_cast<double>(s.program->size()) / 2);
      frames(hv, iso, k, "iso, timeline half-way");
      hv.renderer().set_progress(*s.program, NAN);
      iso.zoom_at(10, width / 2.0, height / 2.0);
      frames(hv, iso, k, "iso, zoomed in x10");
      // What the window draws while a drag moves the view of a large
      // program: half the resolution, scaled up.
      view.reset();
      view.emplace(width / 2, height / 2);
      load_scene(view->renderer(), s);
      frames(*view, camera_for(s, NamedView::Iso, width / 2, height / 2), k, "iso, half resolution (drag)");
      std::printf("peak memory %.0f MB\n", peak_mb());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_viewer: %s\n", e.what());
    return 1;
  }
  return 0;
}
