// Piecewise-constant 1D and 2D distributions (pbrt's PiecewiseConstant1D/2D), used for
// light selection by power, triangle selection by area and environment importance sampling.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/vec.h"

namespace caustica {

class Distribution1D {
 public:
  Distribution1D() = default;
  // Negative and non-finite weights are treated as 0. An all-zero input becomes uniform.
  explicit Distribution1D(std::vector<float> weights);

  size_t size() const { return func_.size(); }
  float integral() const { return integral_; }
  // Sum of the input weights (the integral over [0, size)).
  float total() const { return integral_ * float(func_.size()); }

  // Discrete: picks index i with probability weight_i / total. *remapped gets u rescaled to
  // [0,1) within the chosen bucket, so one number can drive two decisions.
  size_t sample_discrete(float u, float* pmf, float* remapped = nullptr) const;
  float pmf(size_t i) const;
  // Continuous on [0,1): density pdf(x) = func(x) / integral.
  float sample_continuous(float u, float* pdf, size_t* offset = nullptr) const;
  float pdf_continuous(float x) const;
  // The normalised cumulative weights, size() + 1 entries from 0 to 1.
  const std::vector<float>& cdf() const { return cdf_; }

 private:
  // Largest i in [0, size) with cdf_[i] <= u (u >= 0), as a search of the whole cdf would find.
  size_t find_interval(float u) const;

  std::vector<float> func_, cdf_;
  // Guide table (Chen and Asau 1974): guide_[k] is the largest i with cdf_[i] <= k / G for the
  // G = guide_.size() - 1 (a power of two, about a quarter of the size) equal steps of u, so a
  // search only covers the few entries between guide_[k] and guide_[k + 1] instead of halving
  // the whole table with a dependent cache miss per step (an environment map's rows).
  std::vector<uint32_t> guide_;
  float integral_ = 0;
};

class Distribution2D {
 public:
  Distribution2D() = default;
  // values[v * width + u]; density over [0,1)^2 proportional to the values.
  Distribution2D(const std::vector<float>& values, int width, int height);
  Vec2 sample(Vec2 u, float* pdf) const;
  float pdf(Vec2 p) const;
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  int width_ = 0, height_ = 0;
  std::vector<Distribution1D> conditional_;
  Distribution1D marginal_;
};

}  // namespace caustica
