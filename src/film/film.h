// The film: per-pixel sums of iteration estimates. A pixel is the plain average of its
// estimates: integrators apply the pixel filter by filter importance sampling and weighted splats
// (pixel_filter.h).
//
// Two buffers. The current iteration's estimate is summed in double from zero (a camera sample
// plus splats, a few additions per pixel); end_iteration() adds it exactly, in 64.64 fixed point
// (fixed_sum.h), to the total, and clears it. The total therefore depends only on the set of
// iterations rendered, not on the order or grouping in which they are added: films rendered by
// several processes and summed (add(), or an MPI reduction over sums()) equal, bit for bit, one
// film that rendered all their iterations. Cost: 72 bytes per pixel instead of 24.
//
// Determinism: camera samples are written by the single task that owns the pixel in that
// iteration; light-tracing splats are gathered in per-chunk buffers that the integrator adds
// with add_image() in a fixed order. Nothing depends on thread scheduling.
#pragma once

#include <atomic>
#include <cstdint>
#include <span>
#include <vector>

#include "core/rgb.h"
#include "film/fixed_sum.h"
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
    double* p = &current_[3 * (size_t(y) * width_ + x)];
    p[0] += value.r;
    p[1] += value.g;
    p[2] += value.b;
  }
  // Adds a whole image (e.g. merged light-tracing splats), scaled, to the current iteration.
  void add_image(const Image& image, float scale = 1.f);
  // Counts a discarded non-finite value found by an integrator's own buffers.
  void count_nonfinite(uint64_t n = 1) { nonfinite_.fetch_add(n, std::memory_order_relaxed); }

  // Adds the current iteration exactly to the total and starts the next one from zero.
  void end_iteration();
  uint32_t iterations() const { return iterations_; }
  uint64_t nonfinite_count() const { return nonfinite_.load(); }

  // Average over completed iterations.
  Image image() const;

  // Adds another film's completed iterations (same size): the result is bit-identical to a
  // film that rendered both sets of iterations, in any order.
  void add(const Film& other);
  // The totals of completed iterations, 3 per pixel (RGB), for a reduction across processes.
  std::span<FixedSum> sums() { return total_; }
  std::span<const FixedSum> sums() const { return total_; }
  // After sums() was replaced by a sum over several films: their iteration and discard counts.
  void set_counts(uint32_t iterations, uint64_t nonfinite) {
    iterations_ = iterations;
    nonfinite_.store(nonfinite);
  }

 private:
  int width_, height_;
  std::vector<double> current_;  // this iteration's estimates, summed from zero
  std::vector<FixedSum> total_;  // completed iterations, exactly
  uint32_t iterations_ = 0;
  std::atomic<uint64_t> nonfinite_{0};
};

}  // namespace caustica
