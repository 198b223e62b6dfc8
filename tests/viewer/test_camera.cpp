// The viewer's camera, pure math: named views look where they say, project
// and unproject are inverses, zoom keeps the point under the cursor, pan
// moves the scene with the mouse, fit frames the box.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "cncstream/viewer/camera.hpp"

using namespace cncstream;
using namespace cncstream::viewer;

namespace {

void expect_near(const geometry::Vec3& a, const geometry::Vec3& b, double tol) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

geometry::Box3 box(geometry::Vec3 lo, geometry::Vec3 hi) {
  geometry::Box3 b;
  b.add(lo);
  b.add(hi);
  return b;
}

Camera camera(NamedView v, int w = 400, int h = 300) {
  Camera c;
  c.set_viewport(w, h);
  const geometry::Box3 b = box({0, 0, -10}, {120, 100, 0});
  c.set_scene(b);
  c.set_view(v);
  c.fit(b);
  return c;
}

}  // namespace

TEST(ViewerCamera, NamedViewsLookWhereTheySay) {
  const Camera top = camera(NamedView::Top);
  expect_near(top.back(), {0, 0, 1}, 1e-12);
  expect_near(top.right(), {1, 0, 0}, 1e-12);
  expect_near(top.up(), {0, 1, 0}, 1e-12);
  const Camera front = camera(NamedView::Front);
  expect_near(front.back(), {0, -1, 0}, 1e-12);
  expect_near(front.up(), {0, 0, 1}, 1e-12);
  const Camera side = camera(NamedView::Side);
  expect_near(side.back(), {1, 0, 0}, 1e-12);
  expect_near(side.right(), {0, 1, 0}, 1e-12);
  expect_near(side.up(), {0, 0, 1}, 1e-12);
  const Camera iso = camera(NamedView::Iso);
  expect_near(iso.back(), normalized(geometry::Vec3{1, -1, 1}), 1e-12);
  // A point higher in z is higher on the screen (smaller window y) in the iso view.
  EXPECT_LT(iso.project({60, 50, 10}).y, iso.project({60, 50, 0}).y);
  // Top view: +x to the right, +y up the screen.
  EXPECT_GT(top.project({100, 50, 0}).x, top.project({10, 50, 0}).x);
  EXPECT_LT(top.project({60, 90, 0}).y, top.project({60, 10, 0}).y);
}

TEST(ViewerCamera, ParsesViewNamesAndRejectsOthers) {
  EXPECT_EQ(parse_named_view("side"), NamedView::Side);
  try {
    parse_named_view("bottom");
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("top, front, side or iso"), std::string::npos) << e.what();
  }
}

TEST(ViewerCamera, ProjectAndUnprojectAreInverses) {
  Camera c = camera(NamedView::Iso, 640, 480);
  c.orbit(37, -12);
  c.pan(15, 7);
  c.zoom_at(1.7, 100, 120);
  for (const geometry::Vec3 p : {geometry::Vec3{0, 0, 0}, geometry::Vec3{120, 100, -10}, geometry::Vec3{33.3, 71.2, -4.5}}) {
    const WindowPoint w = c.project(p);
    EXPECT_GT(w.depth, 0);
    EXPECT_LT(w.depth, 1);
    expect_near(c.unproject(w), p, 1e-9);
  }
  // The matrices say the same as project(): GL will put the point there.
  const geometry::Vec3 p{33.3, 71.2, -4.5};
  const Mat4 m = c.view_projection();
  double clip[4];
  for (int r = 0; r < 4; ++r) clip[r] = m.at(r, 0) * p.x + m.at(r, 1) * p.y + m.at(r, 2) * p.z + m.at(r, 3);
  const WindowPoint w = c.project(p);
  EXPECT_NEAR((clip[0] / clip[3] + 1) / 2 * c.width(), w.x, 1e-9);
  EXPECT_NEAR((1 - clip[1] / clip[3]) / 2 * c.height(), w.y, 1e-9);
  EXPECT_NEAR((clip[2] / clip[3] + 1) / 2, w.depth, 1e-12);
}

TEST(ViewerCamera, ZoomKeepsThePointUnderTheCursor) {
  Camera c = camera(NamedView::Iso, 640, 480);
  const geometry::Vec3 p{100, 20, -3};
  const WindowPoint before = c.project(p);
  const double h = c.half_height();
  c.zoom_at(2.5, before.x, before.y);
  const WindowPoint after = c.project(p);
  EXPECT_NEAR(after.x, before.x, 1e-9);
  EXPECT_NEAR(after.y, before.y, 1e-9);
  EXPECT_NEAR(c.half_height(), h / 2.5, 1e-12);
  // Other points move away from the cursor (magnified about it).
  const WindowPoint q0 = camera(NamedView::Iso, 640, 480).project({10, 90, 0});
  const WindowPoint q1 = c.project({10, 90, 0});
  EXPECT_NEAR(q1.x - before.x, 2.5 * (q0.x - before.x), 1e-6);
}

TEST(ViewerCamera, PanMovesTheSceneWithTheMouse) {
  Camera c = camera(NamedView::Iso, 640, 480);
  const geometry::Vec3 p{60, 50, -5};
  const WindowPoint before = c.project(p);
  c.pan(40, -25);
  const WindowPoint after = c.project(p);
  EXPECT_NEAR(after.x - before.x, 40, 1e-9);
  EXPECT_NEAR(after.y - before.y, -25, 1e-9);
  // Far from the scene the depth range still covers it.
  c.pan(5000, 3000);
  const double d = c.project({120, 100, 0}).depth;
  EXPECT_GT(d, 0);
  EXPECT_LT(d, 1);
}

TEST(ViewerCamera, FitFramesTheBoxInEveryView) {
  const geometry::Box3 b = box({-20, 5, -30}, {220, 75, 12});
  for (const NamedView v : {NamedView::Top, NamedView::Front, NamedView::Side, NamedView::Iso})
    for (const auto& [w, h] : {std::pair{400, 300}, std::pair{300, 600}}) {
      Camera c;
      c.set_viewport(w, h);
      c.set_scene(b);
      c.set_view(v);
      c.orbit(0, 0);
      c.fit(b);
      double lo_x = 1e9, hi_x = -1e9, lo_y = 1e9, hi_y = -1e9;
      for (int k = 0; k < 8; ++k) {
        const WindowPoint p = c.project({k & 1 ? b.hi.x : b.lo.x, k & 2 ? b.hi.y : b.lo.y, k & 4 ? b.hi.z : b.lo.z});
        lo_x = std::min(lo_x, p.x), hi_x = std::max(hi_x, p.x), lo_y = std::min(lo_y, p.y), hi_y = std::max(hi_y, p.y);
        EXPECT_GT(p.depth, 0);
        EXPECT_LT(p.depth, 1);
      }
      EXPECT_GE(lo_x, 0);
      EXPECT_LE(hi_x, w);
      EXPECT_GE(lo_y, 0);
      EXPECT_LE(hi_y, h);
      // Tight in one direction: the margin is under 10 % of the window.
      const bool tight_x = hi_x - lo_x > 0.9 * w, tight_y = hi_y - lo_y > 0.9 * h;
      EXPECT_TRUE(tight_x || tight_y) << "view " << static_cast<int>(v) << " " << w << "x" << h;
      // Centred.
      EXPECT_NEAR((lo_x + hi_x) / 2, w / 2.0, 1e-6);
      EXPECT_NEAR((lo_y + hi_y) / 2, h / 2.0, 1e-6);
    }
}

TEST(ViewerCamera, OrbitTurnsAndStopsAtThePoles) {
  Camera c = camera(NamedView::Front);
  c.orbit(-180, 0);  // half a degree a pixel
  EXPECT_NEAR(c.azimuth_deg(), 90, 1e-12);
  c.orbit(0, 1000);
  EXPECT_EQ(c.elevation_deg(), 90);
  c.orbit(0, -5000);
  EXPECT_EQ(c.elevation_deg(), -90);
  EXPECT_THROW(c.set_viewport(0, 10), std::invalid_argument);
}

TEST(ViewerCamera, MaySeeWhatIsInTheViewportOnly) {
  Camera c = camera(NamedView::Top, 400, 300);
  EXPECT_TRUE(c.may_see(box({10, 10, -1}, {20, 20, 0})));
  EXPECT_TRUE(c.may_see(box({-1000, 50, 0}, {1000, 51, 0})));  // crosses the view
  EXPECT_FALSE(c.may_see(box({500, 10, 0}, {600, 20, 0})));
  c.zoom_at(10, 0, 0);  // toward the top-left corner
  EXPECT_FALSE(c.may_see(box({100, 10, 0}, {120, 20, 0})));
  EXPECT_FALSE(c.may_see(geometry::Box3{}));
}
