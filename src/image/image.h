// A float RGB image, stored row-major with the top row first (raster order).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/rgb.h"

namespace caustica {

class Image {
 public:
  Image() = default;
  Image(int width, int height, Rgb fill = Rgb(0.f))
      : width_(width), height_(height), pixels_(size_t(width) * size_t(height), fill) {}

  int width() const { return width_; }
  int height() const { return height_; }
  size_t pixel_count() const { return pixels_.size(); }
  bool empty() const { return pixels_.empty(); }

  Rgb& at(int x, int y) { return pixels_[size_t(y) * width_ + x]; }
  const Rgb& at(int x, int y) const { return pixels_[size_t(y) * width_ + x]; }
  Rgb& operator[](size_t i) { return pixels_[i]; }
  const Rgb& operator[](size_t i) const { return pixels_[i]; }
  std::vector<Rgb>& pixels() { return pixels_; }
  const std::vector<Rgb>& pixels() const { return pixels_; }

  // Bilinear lookup at continuous coordinates st in [0,1)^2 (s right, t down), wrapping.
  Rgb bilinear_wrap(float s, float t) const;
  // The same lookup with pbrt-v4's other wrap modes for texels outside the image: Clamp repeats
  // the edge texels, Black reads 0 (Repeat is bilinear_wrap).
  enum class Wrap { Repeat, Clamp, Black };
  Rgb bilinear(float s, float t, Wrap wrap) const;
  Rgb average() const;

 private:
  int width_ = 0, height_ = 0;
  std::vector<Rgb> pixels_;
};

}  // namespace caustica
