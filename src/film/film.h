// The film: per-pixel sums of iteration estimates, in double precision so long renders do
// not lose small contributions. A pixel is the plain average of its estimates: integrators apply
// the pixel filter by filter importance sampling and weighted splats (pixel_filter.h).
//
// Determinism: camera samples are written by the single task that owns the pixel in that
// iteration; light-tracing splats are gathered in per-chunk buffers that the integrator adds
// with add_image() in a fixed order. Nothing depends on thread scheduling.
#pragma once

#include <atomic>
#include <cstdint>
#include <vector>

#include "core/rgb.h"
#include "image/image.h"

namespace caustica {

class Film {
 public:
  Film(int width, int height);

  int width() const { return width_; }
  int height() const { return height_; }
  size_t pixel_count() const { return size_t(width_) * size_t(height_); }

  // Adds one estimate to pixel (x, y) for the current iteration. Non-finite values are
  // discarded and counted: NaN/Inf never reach the image. Negative values are kept: filters
  // with negative lobes (mitchell, sinc) give negative sample weights.
  void add_sample(int x, int y, Rgb value) {
    if (!value.is_finite()) {
      nonfinite_.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    double* p = &sum_[3 * (size_t(y) * width_ + x)];
    p[0] += value.r;
    p[1] += value.g;
    p[2] += value.b;
  }
  // Adds a whole image (e.g. merged light-tracing splats), scaled, to the current iteration.
  void add_image(const Image& image, float scale = 1.f);
  // Counts a discarded non-finite value found by an integrator's own buffers.
  void count_nonfinite(uint64_t n = 1) { nonfinite_.fetch_add(n, std::memory_order_relaxed); }

  void end_iteration() { ++iterations_; }
  uint32_t iterations() const { return iterations_; }
  uint64_t nonfinite_count() const { return nonfinite_.load(); }

  // Average over completed iterations.
  Image image() const;

 private:
  int width_, height_;
  std::vector<double> sum_;
  uint32_t iterations_ = 0;
  std::atomic<uint64_t> nonfinite_{0};
};

}  // namespace caustica
