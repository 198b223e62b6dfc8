// Screenshots on the EGL surfaceless context (llvmpipe without a GPU),
// judged by image statistics, never exact pixels: the plaque's silhouette
// from the top covers its projected footprint, the depth under a pixel
// unprojects onto the part, a program's cuts, dashed rapids and timeline
// show, and a cut shows the gouge colour only where it is gouged.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "cncstream/cam/deviation.hpp"
#include "cncstream/geometry/stl.hpp"
#include "cncstream/gl/gl_error.hpp"
#include "cncstream/viewer/headless.hpp"

using namespace cncstream;
using namespace cncstream::viewer;

namespace {

constexpr int kSize = 256;

const geometry::Mesh& plaque() {
  static const geometry::Mesh m = geometry::load_stl(CNCSTREAM_SOURCE_DIR "/examples/plaque.stl").mesh;
  return m;
}

struct Frame {
  image::RgbImage image;
  Camera camera;
  std::vector<float> depth;  // a few probed pixels
};

Frame render(const Scene& scene, NamedView view, const std::vector<std::pair<int, int>>& probes = {}) {
  HeadlessView hv(kSize, kSize);
  load_scene(hv.renderer(), scene);
  Frame f{image::RgbImage(), camera_for(scene, view, kSize, kSize), {}};
  hv.draw(f.camera);
  f.image = hv.read_image();
  for (const auto& [x, y] : probes) f.depth.push_back(static_cast<float>(hv.depth_at(x, y)));
  return f;
}

// The mesh's projected footprint: pixel centres inside a projected facet.
std::vector<std::uint8_t> footprint(const geometry::Mesh& mesh, const Camera& cam) {
  std::vector<std::uint8_t> mask(static_cast<std::size_t>(kSize) * kSize, 0);
  for (std::size_t t = 0; t < mesh.size(); ++t) {
    const WindowPoint a = cam.project(mesh.corner(t, 0)), b = cam.project(mesh.corner(t, 1)),
                      c = cam.project(mesh.corner(t, 2));
    const double area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    if (std::fabs(area) < 1e-12) continue;
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x, b.x, c.x}))));
    const int x1 = std::min(kSize - 1, static_cast<int>(std::ceil(std::max({a.x, b.x, c.x}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y, b.y, c.y}))));
    const int y1 = std::min(kSize - 1, static_cast<int>(std::ceil(std::max({a.y, b.y, c.y}))));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        const double w0 = ((b.x - px) * (c.y - py) - (b.y - py) * (c.x - px)) / area;
        const double w1 = ((c.x - px) * (a.y - py) - (c.y - py) * (a.x - px)) / area;
        if (w0 >= 0 && w1 >= 0 && w0 + w1 <= 1) mask[static_cast<std::size_t>(y) * kSize + x] = 1;
      }
  }
  return mask;
}

bool is_background(image::Rgb c) { return c == kBackground; }
bool is_gouge_red(image::Rgb c) { return c.r > c.g + 60 && c.r > c.b + 60; }
bool near(image::Rgb a, image::Rgb b, int tol) {
  return std::abs(a.r - b.r) <= tol && std::abs(a.g - b.g) <= tol && std::abs(a.b - b.b) <= tol;
}

}  // namespace

TEST(ViewerScreenshot, PlaqueSilhouetteFromTheTopCoversItsFootprint) {
  Scene s;
  s.part = part_surface(plaque());
  const Frame f = render(s, NamedView::Top);
  const auto mask = footprint(plaque(), f.camera);
  std::size_t inside = 0, interior_mismatch = 0, edge_mismatch = 0;
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      const bool want = mask[static_cast<std::size_t>(y) * kSize + x];
      inside += want;
      const bool drawn = !is_background(f.image.get(x, y));
      if (want == drawn) continue;
      // Away from the outline the two must agree; on it the rasterizer's
      // rules may differ by a pixel.
      bool uniform = true;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int u = std::clamp(x + dx, 0, kSize - 1), v = std::clamp(y + dy, 0, kSize - 1);
          uniform = uniform && mask[static_cast<std::size_t>(v) * kSize + u] == want;
        }
      (uniform ? interior_mismatch : edge_mismatch) += 1;
    }
  EXPECT_GT(inside, 0.4 * kSize * kSize);  // fitted: the plaque fills much of the frame
  EXPECT_EQ(interior_mismatch, 0u);
  EXPECT_LT(edge_mismatch, inside / 100);
}

TEST(ViewerScreenshot, DepthUnderAPixelUnprojectsOntoThePart) {
  Scene s;
  s.part = part_surface(plaque());
  // Probe the pixels where 25 points of the part's top project.
  cam::GridSpec top = cam::GridSpec::covering(20, 15, 100, 85, 20, 17.5);
  const cam::DesignHeights tops = cam::design_heights(plaque(), top);
  const Camera cam = camera_for(s, NamedView::Iso, kSize, kSize);
  std::vector<std::pair<int, int>> probes;
  for (std::size_t j = 0; j < top.ny; ++j)
    for (std::size_t i = 0; i < top.nx; ++i) {
      const WindowPoint w = cam.project({top.x(i), top.y(j), tops.z[j * top.nx + i]});
      probes.emplace_back(static_cast<int>(w.x), static_cast<int>(w.y));
    }
  ASSERT_EQ(probes.size(), 25u);
  const Frame f = render(s, NamedView::Iso, probes);
  int on_part = 0, agree = 0;
  for (std::size_t k = 0; k < probes.size(); ++k) {
    if (f.depth[k] >= 1.0f) continue;
    ++on_part;
    const geometry::Vec3 p = f.camera.unproject({probes[k].first + 0.5, probes[k].second + 0.5, f.depth[k]});
    cam::GridSpec g;
    g.x0 = p.x, g.y0 = p.y, g.nx = g.ny = 1;
    const cam::DesignHeights h = cam::design_heights(plaque(), g);
    if (!h.off_part[0] && std::fabs(h.z[0] - p.z) < 0.05) ++agree;
  }
  EXPECT_EQ(on_part, 25);
  // A probe on a wall's edge may see the wall, whose top-most hit is higher.
  EXPECT_GE(agree, on_part - 2);
}

TEST(ViewerScreenshot, ProgramShowsCutsDashedRapidsAndTheTimeline) {
  std::string program = "G21 G90 G17\nG0 Z5\nG0 X5 Y10\nG1 Z0 F300\n";
  for (int row = 1; row <= 9; ++row) {
    program += row % 2 ? "G1 X115 F1200\n" : "G1 X5 F1200\n";
    if (row < 9) program += "G1 Y" + std::to_string(10 * (row + 1)) + "\n";
  }
  program += "G0 Z5\nG0 X5 Y97\nG0 X115 Y97\n";
  Scene s;
  s.program = build_toolpath(program);
  ASSERT_EQ(s.program->rapids, 5u);
  const image::Rgb fast = image::colormap_viridis(1);
  auto pixel_at = [](const Frame& f, double x, double y) {
    const WindowPoint w = f.camera.project({x, y, 0});
    return f.image.get(static_cast<int>(w.x), static_cast<int>(w.y));
  };
  // The whole program done: every cutting row in the fast feed's colour.
  {
    const Frame f = render(s, NamedView::Top);
    for (int row = 1; row <= 9; ++row) EXPECT_TRUE(near(pixel_at(f, 60.3, 10.0 * row), fast, 8)) << row;
    // The long rapid at y = 97 is dashed: some of it drawn, some not.
    const WindowPoint a = f.camera.project({10, 97, 5}), b = f.camera.project({110, 97, 5});
    int drawn = 0, gaps = 0;
    for (int x = static_cast<int>(a.x); x <= static_cast<int>(b.x); ++x) {
      const image::Rgb c = f.image.get(x, static_cast<int>(a.y));
      if (near(c, kRapidColour, 8)) ++drawn;
      else if (is_background(c)) ++gaps;
    }
    const int n = static_cast<int>(b.x) - static_cast<int>(a.x) + 1;
    EXPECT_GT(drawn, n / 4);
    EXPECT_GT(gaps, n / 4);
    EXPECT_GE(drawn + gaps, n - 2);
  }
  // Half-way: the first rows bright, the last dim; the cutter where the
  // timeline is.
  {
    s.progress = static_cast<double>(s.program->size()) / 2;
    s.cutter = cam::Cutter::ball(6);
    const geometry::Vec3 tip = s.program->point_at(s.progress);
    const Frame f = render(s, NamedView::Top);
    EXPECT_TRUE(near(pixel_at(f, 60.3, 10), fast, 8));
    const image::Rgb dim = pixel_at(f, 60.3, 90);
    EXPECT_FALSE(near(dim, fast, 40));
    EXPECT_GT(dim.b, fast.b + 100);  // faded toward the background
    const WindowPoint c = f.camera.project(tip);
    const image::Rgb under_cutter = f.image.get(static_cast<int>(c.x), static_cast<int>(c.y));
    EXPECT_FALSE(is_background(under_cutter));
    EXPECT_FALSE(near(under_cutter, fast, 40));
    EXPECT_LT(std::abs(under_cutter.r - under_cutter.b), 40);  // the cutter's grey
  }
}

TEST(ViewerScreenshot, GougeColourOnlyWhereTheCutIsGouged) {
  cam::GridSpec g = cam::GridSpec::covering(-2, -2, 122, 102, 1, 1);
  const cam::DesignHeights d = cam::design_heights(plaque(), g);
  const double floor = plaque().bounds().lo.z;
  std::vector<float> clean(g.size());
  for (std::size_t k = 0; k < g.size(); ++k) clean[k] = static_cast<float>(d.off_part[k] ? floor : d.z[k]);
  std::vector<float> gouged = clean;
  for (std::size_t j = 0; j < g.ny; ++j)
    for (std::size_t i = 0; i < g.nx; ++i)
      if (g.x(i) >= 50 && g.x(i) <= 60 && g.y(j) >= 40 && g.y(j) <= 50) gouged[j * g.nx + i] -= 1.0f;
  auto count = [&](const std::vector<float>& z, std::size_t& red, std::size_t& green, std::size_t& gouged_nodes) {
    Scene s;
    s.cut = cut_surface(g, z, plaque(), 0.05);
    gouged_nodes = s.cut->stats.gouged;
    const Frame f = render(s, NamedView::Top);
    red = green = 0;
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        const image::Rgb c = f.image.get(x, y);
        red += is_gouge_red(c);
        green += near(c, image::DeviationPalette::within, 6);
      }
  };
  std::size_t red = 0, green = 0, nodes = 0;
  count(clean, red, green, nodes);
  EXPECT_EQ(nodes, 0u);
  EXPECT_EQ(red, 0u);
  EXPECT_GT(green, kSize * kSize / 3u);
  count(gouged, red, green, nodes);
  EXPECT_EQ(nodes, 121u);  // 11 x 11 nodes
  EXPECT_GT(red, 150u);    // a 10 mm square at about half a millimetre a pixel
  EXPECT_LT(red, 800u);
}

TEST(ViewerScreenshot, NoContextIsAClearError) {
  try {
    HeadlessView hv(64, 64, 0x1234);
    FAIL() << "made a context on a made-up EGL platform";
  } catch (const gl::GlError& e) {
    EXPECT_NE(std::string(e.what()).find("EGL"), std::string::npos) << e.what();
  }
}
