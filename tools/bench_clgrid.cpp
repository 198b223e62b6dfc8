// CL engine benchmark: for each mesh x cutter x grid step, the wall time of
// ClEngine::compute() over the mesh's XY bounds (and the CPU time it took,
// all threads, to judge a shared machine), nodes per second and the
// process's peak memory (getrusage ru_maxrss, which only grows: run one case
// per process to read a case's own peak).
//
//   bench_clgrid                         the standard matrix (plaque, lion relief, 600k synthetic)
//   bench_clgrid --mesh plaque --cutter ball:6 --step 0.1 [--threads N] [--repeat K]
//   --mesh takes plaque | lion | housing | synthetic600k | a path to an STL file (--scale k applies).
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "cncstream/cam/cl_engine.hpp"
#include "cncstream/geometry/stl.hpp"

using namespace cncstream;

namespace {

double peak_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;  // KiB on Linux
}

double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// A dense, welded height field over 120 x 100 mm: smooth waves (ridges and
// valleys), a raised plateau with vertical-ish walls and a groove, so every
// primitive kind matters. 2 * nx * ny facets.
geometry::Mesh synthetic_relief(std::size_t nx, std::size_t ny) {
  geometry::Mesh m;
  const double W = 120, H = 100;
  m.vertices.reserve((nx + 1) * (ny + 1));
  for (std::size_t j = 0; j <= ny; ++j)
    for (std::size_t i = 0; i <= nx; ++i) {
      const double x = W * static_cast<double>(i) / static_cast<double>(nx);
      const double y = H * static_cast<double>(j) / static_cast<double>(ny);
      double z = 4 + 1.5 * std::sin(x / 6.0) * std::cos(y / 4.5) + 0.4 * std::sin(x / 1.7 + y / 2.3);
      if (std::hypot(x - 80, y - 50) < 18) z = 9;                        // plateau
      if (std::fabs(x - 30) < 1.2 && y > 20 && y < 80) z -= 2.5;         // groove
      m.vertices.push_back({x, y, z});
    }
  m.triangles.reserve(2 * nx * ny);
  const auto idx = [&](std::size_t i, std::size_t j) { return static_cast<std::uint32_t>(j * (nx + 1) + i); };
  for (std::size_t j = 0; j < ny; ++j)
    for (std::size_t i = 0; i < nx; ++i) {
      m.triangles.push_back({idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)});
      m.triangles.push_back({idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)});
    }
  return m;
}

// Fit a unit-less or metre mesh to about `size` mm across in XY, base at z = 0.
void fit(geometry::Mesh& m, double size) {
  geometry::Box3 b = m.bounds();
  const geometry::Vec3 s = b.size();
  m.scale(size / std::fmax(s.x, s.y));
  b = m.bounds();
  m.translate({-b.lo.x, -b.lo.y, -b.lo.z});
}

geometry::Mesh load_named(const std::string& name, double scale) {
  const std::string shared = CNCSTREAM_SOURCE_DIR "/../shared/meshes/";
  if (name == "synthetic600k") return synthetic_relief(600, 500);
  if (name == "plaque") return geometry::load_stl(CNCSTREAM_SOURCE_DIR "/examples/plaque.stl").mesh;
  if (name == "lion") {
    geometry::Mesh m = geometry::load_stl(shared + "lion_head_relief.stl").mesh;
    fit(m, 120);
    return m;
  }
  if (name == "housing") {
    geometry::Mesh m = geometry::load_stl(shared + "tr12j_housing_occt.stl").mesh;
    fit(m, 120);
    return m;
  }
  geometry::Mesh m = geometry::load_stl(name).mesh;
  if (scale != 1) m.scale(scale);
  return m;
}

void run_case(const std::string& mesh_name, const geometry::Mesh& mesh, const std::string& cutter_spec, double step,
              unsigned threads, int repeat) {
  const cam::Cutter cutter = cam::parse_cutter_spec(cutter_spec);
  cam::ClOptions opt;
  opt.threads = threads;
  const double t0 = now();
  const cam::ClEngine engine(mesh, cutter, opt);
  const double t_setup = now() - t0;
  const geometry::Box3 b = mesh.bounds();
  const cam::GridSpec spec = cam::GridSpec::covering(b.lo.x, b.lo.y, b.hi.x, b.hi.y, step, step);
  double best = HUGE_VAL, best_cpu = HUGE_VAL;
  std::size_t touched = 0;
  for (int r = 0; r < repeat; ++r) {
    const double t1 = now(), c1 = cpu_seconds();
    const cam::ClGrid g = engine.compute(spec);
    best = std::fmin(best, now() - t1);
    best_cpu = std::fmin(best_cpu, cpu_seconds() - c1);
    touched = 0;
    for (auto f : g.on_floor) touched += f == 0;
  }
  const double mesh_mb = static_cast<double>(mesh.vertices.size() * sizeof(geometry::Vec3) + mesh.triangles.size() * 12) / 1048576.0;
  const double grid_mb = static_cast<double>(spec.size() * 9) / 1048576.0;
  const cam::ClEngineStats& s = engine.stats();
  std::printf("%-14s %-10s %5.2f %8zu %9zu %7.3f %7.3f %7.3f %9.2f %8.1f %8.1f  edges %zu/%zu verts %zu/%zu touched %zu\n",
              mesh_name.c_str(), cutter_spec.c_str(), step, mesh.triangles.size(), spec.size(), t_setup, best, best_cpu,
              static_cast<double>(spec.size()) / best / 1e6, peak_mb(), 2 * (mesh_mb + grid_mb) + 50, s.edges_drawn,
              s.edges, s.vertices_drawn, s.vertices, touched);
  std::fflush(stdout);
}

void header() {
  std::printf("%-14s %-10s %5s %8s %9s %7s %7s %7s %9s %8s %8s\n", "mesh", "cutter", "step", "facets", "nodes",
              "setup_s", "wall_s", "cpu_s", "Mnodes/s", "peak_MB", "budgetMB");
}

}  // namespace

int main(int argc, char** argv) {
  try {
    std::string mesh_name, cutter_spec;
    double step = 0.1, scale = 1;
    unsigned threads = 0;
    int repeat = 1;
    for (int k = 1; k < argc; ++k) {
      auto next = [&]() -> std::string {
        if (k + 1 >= argc) throw std::invalid_argument(std::string("missing value after ") + argv[k]);
        return argv[++k];
      };
      if (!std::strcmp(argv[k], "--mesh")) mesh_name = next();
      else if (!std::strcmp(argv[k], "--cutter")) cutter_spec = next();
      else if (!std::strcmp(argv[k], "--step")) step = std::stod(next());
      else if (!std::strcmp(argv[k], "--scale")) scale = std::stod(next());
      else if (!std::strcmp(argv[k], "--threads")) threads = static_cast<unsigned>(std::stoul(next()));
      else if (!std::strcmp(argv[k], "--repeat")) repeat = std::stoi(next());
      else throw std::invalid_argument(std::string("unknown argument ") + argv[k]);
    }
    header();
    const std::vector<std::string> cutters =
        cutter_spec.empty() ? std::vector<std::string>{"ball:6", "flat:6", "bull:6:1"} : std::vector<std::string>{cutter_spec};
    const std::vector<std::string> meshes =
        mesh_name.empty() ? std::vector<std::string>{"plaque", "lion", "synthetic600k"} : std::vector<std::string>{mesh_name};
    for (const auto& name : meshes) {
      const geometry::Mesh mesh = load_named(name, scale);
      for (const auto& c : cutters) run_case(name, mesh, c, step, threads, repeat);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_clgrid: %s\n", e.what());
    return 1;
  }
  return 0;
}
