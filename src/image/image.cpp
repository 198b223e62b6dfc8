// RgbImage: storage, pixel access and the simple drawing operations.
#include <algorithm>
#include <stdexcept>
#include <string>

#include "cncstream/image/image.hpp"

namespace cncstream::image {

RgbImage::RgbImage(int width, int height, Rgb fill) : w_(width), h_(height) {
  if (width < 0 || height < 0 || (width > 0 && height > (1 << 30) / 3 / width))
    throw std::invalid_argument("image size " + std::to_string(width) + " x " + std::to_string(height) +
                                " is not allowed");
  px_.resize(static_cast<std::size_t>(w_) * static_cast<std::size_t>(h_) * 3);
  for (std::size_t k = 0; k < px_.size(); k += 3) {
    px_[k] = fill.r;
    px_[k + 1] = fill.g;
    px_[k + 2] = fill.b;
  }
}

Rgb RgbImage::get(int x, int y) const {
  if (x < 0 || y < 0 || x >= w_ || y >= h_)
    throw std::out_of_range("pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") is outside the " +
                            std::to_string(w_) + " x " + std::to_string(h_) + " image");
  const std::size_t k = (static_cast<std::size_t>(y) * static_cast<std::size_t>(w_) + static_cast<std::size_t>(x)) * 3;
  return {px_[k], px_[k + 1], px_[k + 2]};
}

void RgbImage::set(int x, int y, Rgb c) {
  if (x < 0 || y < 0 || x >= w_ || y >= h_) return;
  const std::size_t k = (static_cast<std::size_t>(y) * static_cast<std::size_t>(w_) + static_cast<std::size_t>(x)) * 3;
  px_[k] = c.r;
  px_[k + 1] = c.g;
  px_[k + 2] = c.b;
}

void RgbImage::fill_rect(int x, int y, int w, int h, Rgb c) {
  const int x0 = std::max(x, 0), y0 = std::max(y, 0);
  const int x1 = std::min(x + w, w_), y1 = std::min(y + h, h_);
  for (int yy = y0; yy < y1; ++yy)
    for (int xx = x0; xx < x1; ++xx) set(xx, yy, c);
}

void RgbImage::draw_rect(int x, int y, int w, int h, Rgb c) {
  if (w <= 0 || h <= 0) return;
  fill_rect(x, y, w, 1, c);
  fill_rect(x, y + h - 1, w, 1, c);
  fill_rect(x, y, 1, h, c);
  fill_rect(x + w - 1, y, 1, h, c);
}

void RgbImage::blit(const RgbImage& src, int x, int y) {
  for (int yy = 0; yy < src.h_; ++yy)
    for (int xx = 0; xx < src.w_; ++xx) set(x + xx, y + yy, src.get(xx, yy));
}

}  // namespace cncstream::image
