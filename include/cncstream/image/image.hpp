#pragma once
// RGB raster images, PNG output, colour maps and labelled legends: the
// pictures a person reads (height maps, deviation maps, choice maps).
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace cncstream::image {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb&) const = default;
};

class RgbImage {
 public:
  RgbImage() = default;
  RgbImage(int width, int height, Rgb fill = {255, 255, 255});

  int width() const { return w_; }
  int height() const { return h_; }
  Rgb get(int x, int y) const;
  void set(int x, int y, Rgb c);  // ignores points outside
  void fill_rect(int x, int y, int w, int h, Rgb c);
  void draw_rect(int x, int y, int w, int h, Rgb c);  // outline
  // Built-in bitmap font (printable ASCII); scale = pixel size of a font dot.
  void draw_text(int x, int y, const std::string& text, Rgb c, int scale = 1);
  static int text_width(const std::string& text, int scale = 1);
  static int text_height(int scale = 1);
  // Copy `src` with its top-left corner at (x, y).
  void blit(const RgbImage& src, int x, int y);
  const std::vector<std::uint8_t>& pixels() const { return px_; }

 private:
  int w_ = 0, h_ = 0;
  std::vector<std::uint8_t> px_;  // RGB, row-major, top row first
};

// Throws std::runtime_error naming the path on failure.
void write_png(const std::filesystem::path& path, const RgbImage& image);
// Reads an 8-bit RGB/RGBA/grey PNG (tests look at what was written).
RgbImage read_png(const std::filesystem::path& path);
// The same in memory (a PNG sent over HTTP); both throw std::runtime_error.
std::string encode_png(const RgbImage& image);
RgbImage decode_png(std::string_view bytes);

// t in [0, 1] -> colour.
Rgb colormap_viridis(double t);
// t in [-1, 1]: blue (negative) - white (0) - red (positive).
Rgb colormap_diverging(double t);

}  // namespace cncstream::image
