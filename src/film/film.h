// The film: per-pixel sums of iteration estimates. A pixel is the plain average of its
// estimates: integrators apply the pixel filter by filter importance sampling and weighted splats
// (pixel_filter.h).
//
// One buffer: every estimate is added exactly, in 64.64 fixed point (core/fixed_sum.h), to the
// pixel's total as it arrives. Integer addition is associative, so the total depends only on the
// set of estimates added, not on the order or grouping in which they are added: films rendered
// by several processes and summed (add(), or an MPI reduction over sums()) equal, bit for bit,
// one film that rendered all their iterations. Cost: 48 bytes per pixel (an earlier version
// also kept a double buffer for the current iteration: 72).
//
// Against summing an iteration in double first (that earlier version): a float estimate above
// 2^-41 converts exactly, so the fixed-point sum of a pixel's estimates is their exact sum, where
// the double sum could round; the image can therefore differ from that version's only where a
// double sum rounded and the rounding reached the final float (never seen in practice).
//
// Determinism: camera samples are written by the single task that owns the pixel in that
// iteration; light-tracing splats are gathered in per-chunk buffers that the integrator adds
// with add_image() in a fixed order. Nothing depends on thread scheduling.
#pragma once

#include <atomic>
#include <cstdint>
#include <span>
#include <vector>

#include "core/fixed_sum.h"
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
    add_exactly(size_t(y) * width_ + x, value);
  }
  // Adds a whole image (e.g. merged light-tracing splats), scaled, to the current iteration.
  // Pixels of value 0 are skipped (adding 0 changes no total).
  void add_image(const Image& image, float scale = 1.f);
  // Counts a discarded non-finite value found by an integrator's own buffers.
  void count_nonfinite(uint64_t n = 1) { nonfinite_.fetch_add(n, std::memory_order_relaxed); }

  // Ends the current iteration: its estimates are already in the totals; this counts it.
  void end_iteration();
  uint32_t iterations() const { return iterations_; }
  uint64_t nonfinite_count() const { return nonfinite_.load(); }

  // Average over completed iterations. Between iterations only: an iteration's estimates are
  // in the totals as soon as they are added, before end_iteration() counts it.
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
  void add_exactly(size_t pixel, Rgb value) {
    FixedSum* p = &total_[3 * pixel];
    p[0] += to_fixed(value.r);
    p[1] += to_fixed(value.g);
    p[2] += to_fixed(value.b);
  }

  std::vector<FixedSum> total_;  // every estimate added so far, exactly
  uint32_t iterations_ = 0;
  std::atomic<uint64_t> nonfinite_{0};
};

}  // namespace caustica
