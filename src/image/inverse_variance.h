// Combines the images of successive rendering passes, each an unbiased estimate of the same
// image with a variance of its own, weighted by the inverse of that variance (Müller 2019,
// "Practical Path Guiding in Production", inverse-variance-based sample combination):
//   I = sum_k I_k / V_k / sum_k 1 / V_k.
// V_k is one number per pass: the mean over pixels of the variance of the pass's pixel mean,
// estimated from the luminance of its samples, s^2 / n with s^2 the unbiased sample variance
// (it needs n >= 2 samples per pixel). A pass with one sample per pixel has no estimate and
// gets weight 0; when no pass has one, image() is empty and the caller uses the plain average.
//
// The weights are estimated from the same samples, so the combination is biased (a ratio
// estimator), but consistent: the bias vanishes as the passes grow. Müller accepts this for the
// much lower variance; the equal-weight average is the unbiased alternative.
//
// Determinism: the current pass's moments are exact fixed-point sums (core/fixed_sum.h), so they
// depend only on which samples were added, not on their order or grouping: the current pass of
// a render split over MPI ranks is summed over the ranks (current_sums()) and gives the
// combination of one process bit for bit. add() has one writer per pixel at a time; V_k is a
// sequential sum over pixels. Memory: 76 bytes per pixel (64 of them the current pass).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "core/fixed_sum.h"
#include "core/rgb.h"
#include "image/image.h"

namespace caustica {

class InverseVarianceCombiner {
 public:
  InverseVarianceCombiner() = default;
  InverseVarianceCombiner(int width, int height);

  // One sample of a pixel (index y * width + x) in the current pass. Non-finite: ignored.
  void add(size_t pixel, Rgb value);
  // Every pixel received its sample of one more iteration of the current pass.
  void end_iteration() {
    if (!current_.empty()) current_.back() += 1;
  }
  // Folds the current pass into the combination and starts the next one.
  void end_pass();

  // The combination of the completed passes and the current one; empty when no pass has two
  // samples per pixel yet.
  Image image() const;

  struct Pass {
    uint32_t samples;  // per pixel
    double variance;   // V_k; negative: no estimate (one sample)
    // The standard error of V_k as a mean over independent pixels (their spread over sqrt of
    // their count): how far another run's V_k would likely be. Negative without an estimate.
    double variance_error = -1;
  };
  // Completed passes, then the current one.
  std::vector<Pass> passes() const;
  size_t bytes() const;

  // The current pass as exact sums (kSumsPerPixel per pixel, then its iteration count), for a
  // sum over processes that each rendered some of its iterations: replaced by their total, they
  // give the combination of one process that rendered them all. clear_current() empties it
  // (a process whose current pass another one holds whole).
  std::span<FixedSum> current_sums() { return current_; }
  void clear_current();
  static constexpr size_t kSumsPerPixel = 4;  // r, g, b, squared luminance

 private:
  // V of the current pass and its standard error; negative without an estimate.
  Pass current_pass() const;
  uint32_t samples() const { return current_.empty() ? 0 : uint32_t(current_.back()); }
  // The current pass's mean of pixel i.
  Rgb mean(size_t i, double n) const;

  int width_ = 0, height_ = 0;
  // Per pixel the sums of r, g, b and the squared luminance of its samples in the current pass;
  // last, the pass's iterations (an integer, not scaled).
  std::vector<FixedSum> current_;
  std::vector<Rgb> combined_;  // sum_k I_k / V_k / sum_k 1 / V_k over completed passes
  double weight_ = 0;          // sum_k 1 / V_k
  std::vector<Pass> completed_;
};

}  // namespace caustica
