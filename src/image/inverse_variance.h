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
// Determinism: add() has one writer per pixel at a time and sums in a fixed order; V_k is a
// sequential sum over pixels. Memory: 44 bytes per pixel.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

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
  void end_iteration() { ++samples_; }
  // Folds the current pass into the combination and starts the next one.
  void end_pass();

  // The combination of the completed passes and the current one; empty when no pass has two
  // samples per pixel yet.
  Image image() const;

  struct Pass {
    uint32_t samples;  // per pixel
    double variance;   // V_k; negative: no estimate (one sample)
  };
  // Completed passes, then the current one.
  std::vector<Pass> passes() const;
  size_t bytes() const;

 private:
  struct Moments {
    double r = 0, g = 0, b = 0;  // sum of the samples
    double luminance2 = 0;       // sum of their squared luminance
  };
  double current_variance() const;  // V of the current pass; negative without an estimate

  int width_ = 0, height_ = 0;
  std::vector<Moments> current_;
  uint32_t samples_ = 0;       // iterations in the current pass
  std::vector<Rgb> combined_;  // sum_k I_k / V_k / sum_k 1 / V_k over completed passes
  double weight_ = 0;          // sum_k 1 / V_k
  std::vector<Pass> completed_;
};

}  // namespace caustica
