#include <gtest/gtest.h>

#include <filesystem>

#include "cncstream/image/image.hpp"

using namespace cncstream;

namespace {
std::filesystem::path out_dir() {
  auto d = std::filesystem::path(CNCSTREAM_BINARY_DIR) / "test-output" / "image";
  std::filesystem::create_directories(d);
  return d;
}
}  // namespace

TEST(Image, FontSheet) {
  image::RgbImage img(16 * 6 * 4 + 16, 7 * 11 * 4 + 16);
  for (int row = 0; row < 6; ++row) {
    std::string s;
    for (int c = 0; c < 16; ++c) {
      const int code = 32 + row * 16 + c;
      if (code < 127) s += static_cast<char>(code);
    }
    img.draw_text(8, 8 + row * 11 * 4, s, {0, 0, 0}, 4);
  }
  img.draw_text(8, 8 + 6 * 44, "Height 12.5 mm gjpqy", {200, 0, 0}, 4);
  image::write_png(out_dir() / "font_sheet.png", img);
}
