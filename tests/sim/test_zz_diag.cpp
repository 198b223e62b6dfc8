#include <gtest/gtest.h>
#include <cstdio>
#include <fstream>
#include "cncstream/cam/stock.hpp"
#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/gcode/interpreter.hpp"
#include "cncstream/gcode/line_lexer.hpp"
#include "cncstream/gcode/arc_segments.hpp"
#include "cncstream/geometry/stl.hpp"
using namespace cncstream;
TEST(ZZDiag, Node) {
  std::ifstream in("/tmp/g/y.nc");
  std::string line; gcode::ParserState s; const Cutter c = parse_cutter_spec("ball:3.175");
  const double nx = 59.0373, ny = 58.2411;
  double best = 1e9; std::string best_line; Vec3 ba, bb; long n = 0, bn = 0;
  auto seg = [&](const Vec3& a, const Vec3& b) {
    const double h = swept_lowest_height(a, b, c, nx, ny);
    if (h < best) { best = h; best_line = line; ba = a; bb = b; bn = n; }
  };
  while (std::getline(in, line)) {
    ++n;
    const auto cl = gcode::clean_line(line).text; if (cl.empty()) continue;
    const auto r = gcode::execute_block(s, cl); if (!r.ok()) continue;
    Vec3 from = s.position;
    for (const auto& a : r.actions) {
      if (const auto* lm = std::get_if<gcode::LinearMove>(&a)) { seg(lm->from, lm->to); }
      else if (const auto* am = std::get_if<gcode::ArcMove>(&a)) { Vec3 p = am->from; for (const Vec3& q : gcode::segment_arc(*am, 0.002)) { seg(p, q); p = q; } }
    }
    (void)from;
    s = r.state;
  }
  std::printf("lowest %.4f at line %ld: %s  from %.4f,%.4f,%.4f to %.4f,%.4f,%.4f\n", best, bn, best_line.c_str(), ba.x, ba.y, ba.z, bb.x, bb.y, bb.z);
  // The CL (work coords: model = work + (0,0,10.5))
  const Mesh mesh = load_stl(std::string(CNCSTREAM_SOURCE_DIR) + "/examples/plaque.stl").mesh;
  const ClEngine e(mesh, c);
  for (int k = 0; k <= 10; ++k) { const Vec3 q = ba + (bb - ba) * (k / 10.0); std::printf("  t %.1f tip z %.4f cl %.4f\n", k/10.0, q.z + 10.5, e.height_at(q.x, q.y)); }
}
