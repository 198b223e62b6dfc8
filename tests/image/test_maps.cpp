// PNG files, colour maps, text and the map renderers' layout.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "cncstream/image/category_map.hpp"
#include "cncstream/image/deviation_map.hpp"
#include "cncstream/image/height_map.hpp"
#include "cncstream/image/image.hpp"

using namespace cncstream;

namespace {

std::filesystem::path out_dir() {
  auto d = std::filesystem::path(CNCSTREAM_BINARY_DIR) / "test-output" / "image";
  std::filesystem::create_directories(d);
  return d;
}

constexpr image::Rgb kWhite{255, 255, 255};

// Nothing drawn in the outer `band` pixels: legends and labels fit inside.
void expect_clear_border(const image::RgbImage& img, int band) {
  for (int y = 0; y < img.height(); ++y)
    for (int x = 0; x < img.width(); ++x)
      if (x < band || y < band || x >= img.width() - band || y >= img.height() - band) {
        ASSERT_EQ(img.get(x, y), kWhite) << "pixel " << x << "," << y << " of " << img.width() << "x"
                                         << img.height();
      }
}

bool contains(const image::RgbImage& img, image::Rgb c, int x0 = 0) {
  for (int y = 0; y < img.height(); ++y)
    for (int x = x0; x < img.width(); ++x)
      if (img.get(x, y) == c) return true;
  return false;
}

// A hill: z = 4 exp(-r^2 / 200) on 60 x 40 mm with a hole of no data.
struct Hill {
  image::MapGrid grid{121, 81, 0.5, 0.5, 0, 0};
  std::vector<double> z;
  std::vector<std::uint8_t> invalid;
  Hill() {
    for (std::size_t j = 0; j < grid.ny; ++j)
      for (std::size_t i = 0; i < grid.nx; ++i) {
        const double x = i * grid.dx - 30, y = j * grid.dy - 20;
        z.push_back(4 * std::exp(-(x * x + y * y) / 200));
        invalid.push_back(std::hypot(x - 20, y - 10) < 4);
      }
  }
};

}  // namespace

TEST(Png, RoundTrip) {
  std::mt19937 rng(7);
  image::RgbImage img(37, 23);
  for (int y = 0; y < img.height(); ++y)
    for (int x = 0; x < img.width(); ++x)
      img.set(x, y, {static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng()),
                     static_cast<std::uint8_t>(rng())});
  const auto path = out_dir() / "roundtrip.png";
  image::write_png(path, img);
  const auto back = image::read_png(path);
  ASSERT_EQ(back.width(), 37);
  ASSERT_EQ(back.height(), 23);
  EXPECT_EQ(back.pixels(), img.pixels());
}

TEST(Png, ErrorsNameThePath) {
  const auto bad = out_dir() / "not_a.png";
  std::ofstream(bad) << "hello";
  for (const auto& p : {bad, out_dir() / "missing.png"}) {
    try {
      image::read_png(p);
      FAIL() << p;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
    }
  }
  try {
    image::write_png(out_dir() / "no_such_dir" / "x.png", image::RgbImage(2, 2));
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_dir"), std::string::npos) << e.what();
  }
}

TEST(Colormap, KnownPoints) {
  EXPECT_EQ(image::colormap_viridis(0), (image::Rgb{68, 1, 84}));
  EXPECT_EQ(image::colormap_viridis(1), (image::Rgb{253, 231, 37}));
  EXPECT_EQ(image::colormap_viridis(-3), image::colormap_viridis(0));
  EXPECT_EQ(image::colormap_viridis(NAN), image::colormap_viridis(0));
  const image::Rgb mid = image::colormap_viridis(0.5);  // between table rows 127 and 128
  EXPECT_NEAR(mid.r, 33, 1);
  EXPECT_NEAR(mid.g, 145, 1);
  EXPECT_NEAR(mid.b, 140, 1);
  // Luminance rises monotonically: the point of viridis.
  double last = -1;
  for (int k = 0; k <= 100; ++k) {
    const image::Rgb c = image::colormap_viridis(k / 100.0);
    const double l = 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
    EXPECT_GT(l, last - 0.5);
    last = l;
  }
  EXPECT_EQ(image::colormap_diverging(0), (image::Rgb{255, 255, 255}));
  EXPECT_EQ(image::colormap_diverging(-1), (image::Rgb{5, 48, 97}));
  EXPECT_EQ(image::colormap_diverging(1), (image::Rgb{103, 0, 31}));
  EXPECT_GT(image::colormap_diverging(-0.5).b, image::colormap_diverging(-0.5).r);
  EXPECT_GT(image::colormap_diverging(0.5).r, image::colormap_diverging(0.5).b);
}

TEST(Text, GlyphDotsLandWhereDrawn) {
  image::RgbImage img(40, 20);
  const image::Rgb ink{0, 0, 0};
  img.draw_text(2, 3, "T", ink, 2);
  // 'T': the top row full, then the middle column.
  for (int k = 0; k < 5; ++k) EXPECT_EQ(img.get(2 + 2 * k, 3), ink) << k;
  EXPECT_EQ(img.get(2 + 4, 3 + 2 * 6), ink);
  EXPECT_EQ(img.get(2, 3 + 2 * 6), kWhite);
  EXPECT_EQ(image::RgbImage::text_width("T", 2), 10);
  EXPECT_EQ(image::RgbImage::text_width("ab", 1), 11);
  EXPECT_EQ(image::RgbImage::text_height(3), 27);
  // Every printable character leaves some ink, except the space.
  for (int c = 33; c < 127; ++c) {
    image::RgbImage g(8, 12);
    g.draw_text(1, 1, std::string(1, static_cast<char>(c)), ink);
    EXPECT_TRUE(contains(g, ink)) << static_cast<char>(c);
  }
  image::RgbImage sp(8, 12);
  sp.draw_text(1, 1, " ", ink);
  EXPECT_FALSE(contains(sp, ink));
}

TEST(Image, DrawingClipsAndBlits) {
  image::RgbImage img(10, 10);
  img.fill_rect(-5, -5, 8, 8, {1, 2, 3});
  EXPECT_EQ(img.get(0, 0), (image::Rgb{1, 2, 3}));
  EXPECT_EQ(img.get(2, 2), (image::Rgb{1, 2, 3}));
  EXPECT_EQ(img.get(3, 3), kWhite);
  img.draw_rect(4, 4, 4, 4, {9, 9, 9});
  EXPECT_EQ(img.get(4, 7), (image::Rgb{9, 9, 9}));
  EXPECT_EQ(img.get(5, 5), kWhite);
  image::RgbImage dst(20, 20, {0, 0, 0});
  dst.blit(img, 15, 15);
  EXPECT_EQ(dst.get(15, 15), (image::Rgb{1, 2, 3}));
  EXPECT_EQ(dst.get(14, 14), (image::Rgb{0, 0, 0}));
  EXPECT_THROW(img.get(10, 0), std::out_of_range);
  EXPECT_THROW(image::RgbImage(-1, 2), std::invalid_argument);
}

TEST(HeightMap, ReliefWithLegendInsideTheImage) {
  Hill h;
  image::HeightMapOptions o;
  o.title = "Hill 4 mm";
  o.subtitle = "test relief, 0.5 mm grid";
  o.max_map_pixels = 600;
  const auto img = image::render_height_map(h.grid, h.z, h.invalid, o);
  image::write_png(out_dir() / "height_map.png", img);
  expect_clear_border(img, 8);
  // The colour bar's ends are the ramp's ends, right of the map.
  EXPECT_TRUE(contains(img, image::colormap_viridis(1), 16 + 600));
  EXPECT_TRUE(contains(img, image::colormap_viridis(0), 16 + 600));
  // The lit (north-west) flank is brighter than the shaded (south-east) one.
  // Map: 60.5 x 40.5 mm at 600/60.5 px per mm, top-left at (16, top).
  // The map's top border: a long run of ink (no text makes one).
  int top = 0;
  auto border_row = [&](int y) {
    for (int x = 15; x < 200; ++x)
      if (img.get(x, y) != image::Rgb{25, 25, 25}) return false;
    return true;
  };
  while (!border_row(top)) ++top;
  ++top;
  const double ppm = 600 / 60.5;
  auto px = [&](double x, double y) {
    return img.get(16 + static_cast<int>((x + 30.25) * ppm), top + static_cast<int>((20.25 - y) * ppm));
  };
  auto lum = [](image::Rgb c) { return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b; };
  EXPECT_GT(lum(px(-7, 7)), lum(px(7, -7)) + 20);
  // The hole shows the no-data grey.
  EXPECT_EQ(px(20, 10), (image::Rgb{205, 205, 205}));
}

TEST(HeightMap, RejectsBadInput) {
  Hill h;
  EXPECT_THROW(image::render_height_map(h.grid, std::span(h.z).first(10), {}, {}), std::invalid_argument);
  EXPECT_THROW(image::render_height_map(image::MapGrid{}, {}, {}, {}), std::invalid_argument);
}

TEST(DeviationMap, GougeAndExcessColoursDiffer) {
  image::MapGrid g{50, 30, 0.2, 0.2, 0, 0};
  std::vector<double> dev(g.size(), 0.01);
  std::vector<std::uint8_t> off(g.size(), 0);
  for (std::size_t j = 0; j < g.ny; ++j)
    for (std::size_t i = 0; i < g.nx; ++i) {
      if (i < 10) dev[j * g.nx + i] = -0.3;
      if (i >= 40) dev[j * g.nx + i] = 0.5;
      if (j < 3) off[j * g.nx + i] = 1;
    }
  image::DeviationMapOptions o;
  o.title = "Deviation";
  o.tolerance = 0.05;
  o.max_map_pixels = 300;
  const auto img = image::render_deviation_map(g, dev, off, o);
  image::write_png(out_dir() / "deviation_map.png", img);
  expect_clear_border(img, 8);
  EXPECT_TRUE(contains(img, image::DeviationPalette::gouge(1)));
  EXPECT_TRUE(contains(img, image::DeviationPalette::excess(1)));
  EXPECT_TRUE(contains(img, image::DeviationPalette::within));
  EXPECT_TRUE(contains(img, image::DeviationPalette::off_part));
  const image::Rgb gouge = image::DeviationPalette::gouge(0.5), excess = image::DeviationPalette::excess(0.5);
  EXPECT_GT(gouge.r, gouge.b + 60);
  EXPECT_GT(excess.b, excess.r + 60);
}

TEST(DeviationMap, OneNodeGougeSurvivesDownsampling) {
  image::MapGrid g{1000, 1000, 0.1, 0.1, 0, 0};
  std::vector<double> dev(g.size(), 0.0);
  dev[500 * 1000 + 500] = -1.0;
  image::DeviationMapOptions o;
  o.max_map_pixels = 100;  // 10 nodes per pixel
  const auto img = image::render_deviation_map(g, dev, {}, o);
  EXPECT_TRUE(contains(img, image::DeviationPalette::gouge(1)));
}

TEST(CategoryMap, SwatchesAndRegions) {
  image::MapGrid g{80, 40, 0.5, 0.5, 0, 0};
  std::vector<int> cat(g.size());
  for (std::size_t j = 0; j < g.ny; ++j)
    for (std::size_t i = 0; i < g.nx; ++i) cat[j * g.nx + i] = i < 20 ? -1 : (i < 50 ? 0 : (j < 20 ? 1 : 2));
  const std::vector<image::MapCategory> names = {{"ball 6 mm", image::category_colour(0)},
                                          {"ball 3.175 mm", image::category_colour(1)},
                                          {"bull 6 mm r1", image::category_colour(2)}};
  image::CategoryMapOptions o;
  o.title = "Cutter choice";
  o.max_map_pixels = 400;
  const auto img = image::render_category_map(g, cat, names, o);
  image::write_png(out_dir() / "category_map.png", img);
  expect_clear_border(img, 8);
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(contains(img, image::category_colour(k), 16 + 400)) << k;  // legend swatches
  EXPECT_NE(image::category_colour(0), image::category_colour(1));
  cat[0] = 3;
  EXPECT_THROW(image::render_category_map(g, cat, names, o), std::invalid_argument);
}
