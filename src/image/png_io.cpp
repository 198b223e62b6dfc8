// PNG files and in-memory PNG through libpng's simplified API (no setjmp in
// our code).
#include <png.h>

#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "cncstream/image/image.hpp"

namespace cncstream::image {

namespace {

png_image rgb_info(const RgbImage& image) {
  png_image info;
  std::memset(&info, 0, sizeof info);
  info.version = PNG_IMAGE_VERSION;
  info.width = static_cast<png_uint_32>(image.width());
  info.height = static_cast<png_uint_32>(image.height());
  info.format = PNG_FORMAT_RGB;
#ifdef PNG_IMAGE_FLAG_FAST
  // Maps are written on every report and verify, previews on request; speed
  // matters more than the last few per cent of file size.
  info.flags |= PNG_IMAGE_FLAG_FAST;
#endif
  return info;
}

// The decoded pixels of a read begun on `info` (from a file or memory).
RgbImage finish_read(png_image& info, const std::string& what) {
  info.format = PNG_FORMAT_RGB;  // libpng converts grey/alpha/palette/16-bit for us
  const int w = static_cast<int>(info.width), h = static_cast<int>(info.height);
  std::vector<std::uint8_t> buf(PNG_IMAGE_SIZE(info));
  if (!png_image_finish_read(&info, nullptr, buf.data(), 0, nullptr)) {
    const std::string why = info.message;
    png_image_free(&info);
    throw std::runtime_error(what + ": cannot decode PNG (" + why + ")");
  }
  RgbImage out(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t k = (static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)) * 3;
      out.set(x, y, {buf[k], buf[k + 1], buf[k + 2]});
    }
  return out;
}

}  // namespace

void write_png(const std::filesystem::path& path, const RgbImage& image) {
  if (image.width() <= 0 || image.height() <= 0)
    throw std::runtime_error(path.string() + ": cannot write an empty image as PNG");
  png_image info = rgb_info(image);
  const int ok = png_image_write_to_file(&info, path.string().c_str(), 0, image.pixels().data(),
                                         image.width() * 3, nullptr);
  if (!ok) {
    const std::string why = info.message;
    png_image_free(&info);
    throw std::runtime_error(path.string() + ": cannot write PNG (" + why + ")");
  }
}

RgbImage read_png(const std::filesystem::path& path) {
  png_image info;
  std::memset(&info, 0, sizeof info);
  info.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&info, path.string().c_str())) {
    const std::string why = info.message;
    png_image_free(&info);
    throw std::runtime_error(path.string() + ": cannot read PNG (" + why + ")");
  }
  return finish_read(info, path.string());
}

std::string encode_png(const RgbImage& image) {
  if (image.width() <= 0 || image.height() <= 0) throw std::runtime_error("cannot encode an empty image as PNG");
  png_image info = rgb_info(image);
  // First the size, then the bytes (libpng's two-call protocol).
  png_alloc_size_t size = 0;
  if (!png_image_write_to_memory(&info, nullptr, &size, 0, image.pixels().data(), image.width() * 3, nullptr)) {
    const std::string why = info.message;
    png_image_free(&info);
    throw std::runtime_error("cannot encode PNG (" + why + ")");
  }
  std::string out(size, '\0');
  if (!png_image_write_to_memory(&info, out.data(), &size, 0, image.pixels().data(), image.width() * 3, nullptr)) {
    const std::string why = info.message;
    png_image_free(&info);
    throw std::runtime_error("cannot encode PNG (" + why + ")");
  }
  out.resize(size);
  return out;
}

RgbImage decode_png(std::string_view bytes) {
  png_image info;
  std::memset(&info, 0, sizeof info);
  info.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&info, bytes.data(), bytes.size())) {
    const std::string why = info.message;
    png_image_free(&info);
    throw std::runtime_error("cannot read PNG (" + why + ")");
  }
  return finish_read(info, "PNG in memory");
}

}  // namespace cncstream::image
