// In-memory PNG and the bare height image a preview sends: its size, where
// its edges lie, and colours that give the height back.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "cncstream/image/height_map.hpp"
#include "cncstream/image/image.hpp"

using namespace cncstream;

namespace {

// The t in [0, 1] whose viridis colour is nearest to c.
double ramp_position(image::Rgb c) {
  double best = -1, dist = 1e9;
  for (int k = 0; k <= 255; ++k) {
    const image::Rgb v = image::colormap_viridis(k / 255.0);
    const double d = std::hypot(v.r - c.r, v.g - c.g, v.b - c.b);
    if (d < dist) {
      dist = d;
      best = k / 255.0;
    }
  }
  return best;
}

}  // namespace

TEST(Png, InMemoryRoundTrip) {
  std::mt19937 rng(11);
  image::RgbImage img(19, 31);
  for (int y = 0; y < img.height(); ++y)
    for (int x = 0; x < img.width(); ++x)
      img.set(x, y, {static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng())});
  const std::string bytes = image::encode_png(img);
  ASSERT_GT(bytes.size(), 8u);
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  const image::RgbImage back = image::decode_png(bytes);
  ASSERT_EQ(back.width(), 19);
  ASSERT_EQ(back.height(), 31);
  EXPECT_EQ(back.pixels(), img.pixels());
  EXPECT_THROW(image::decode_png("not a png"), std::runtime_error);
  EXPECT_THROW(image::encode_png(image::RgbImage()), std::runtime_error);
}

TEST(HeightImage, ColoursGiveTheHeightBackAndEdgesLieOnTheNodes) {
  // z = x on 11 x 3 nodes 1 mm apart: the ramp runs west to east.
  image::MapGrid g{11, 3, 1.0, 1.0, 0, 0};
  std::vector<float> z;
  for (std::size_t j = 0; j < g.ny; ++j)
    for (std::size_t i = 0; i < g.nx; ++i) z.push_back(static_cast<float>(i));
  image::HeightImageOptions o;
  o.width = 100;
  o.height = 20;
  o.z_min = 0;
  o.z_max = 10;
  const image::RgbImage img = image::render_height_image(g, z, o);
  ASSERT_EQ(img.width(), 100);
  ASSERT_EQ(img.height(), 20);
  for (int px : {0, 25, 50, 75, 99}) {
    // Pixel centre x = (px + 0.5) / 100 * 10 mm: its height over the 10 mm ramp.
    const double want = (px + 0.5) / 100.0;
    EXPECT_NEAR(ramp_position(img.get(px, 10)), want, 0.01) << px;
  }
  // Outside the ramp's range the colour saturates.
  o.z_max = 5;
  const image::RgbImage clipped = image::render_height_image(g, z, o);
  EXPECT_EQ(clipped.get(99, 10), image::colormap_viridis(1));
}

TEST(HeightImage, NorthIsUpAndHolesKeepTheNoDataColour) {
  // z = y on 2 x 5 nodes, with the northern row missing.
  image::MapGrid g{2, 5, 1.0, 1.0, 0, 0};
  std::vector<float> z;
  for (std::size_t j = 0; j < g.ny; ++j)
    for (std::size_t i = 0; i < g.nx; ++i)
      z.push_back(j == 4 ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(j));
  image::HeightImageOptions o;
  o.width = 10;
  o.height = 40;
  o.z_min = 0;
  o.z_max = 3;
  o.no_data = {1, 2, 3};
  const image::RgbImage img = image::render_height_image(g, z, o);
  EXPECT_EQ(img.get(5, 0), (image::Rgb{1, 2, 3}));    // the north edge: the missing row
  EXPECT_LT(ramp_position(img.get(5, 39)), 0.03);  // the south edge, lowest
  EXPECT_GT(ramp_position(img.get(5, 12)), ramp_position(img.get(5, 30)));
}

TEST(HeightImage, RejectsBadInput) {
  image::MapGrid g{2, 2, 1, 1, 0, 0};
  const std::vector<float> four(4, 1.0f), three(3, 1.0f);
  image::HeightImageOptions o;
  o.width = o.height = 8;
  EXPECT_NO_THROW(image::render_height_image(g, four, o));
  EXPECT_THROW(image::render_height_image(g, three, o), std::invalid_argument);
  o.width = 0;
  EXPECT_THROW(image::render_height_image(g, four, o), std::invalid_argument);
  o.width = 8;
  EXPECT_THROW(image::render_height_image(image::MapGrid{}, {}, o), std::invalid_argument);
}
