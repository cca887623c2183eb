#include "image/inverse_variance.h"

#include <algorithm>
#include <cmath>

namespace caustica {

namespace {

// The squared luminances are summed times 2^-32: fixed-point sums clamp a value at 2^31, and a
// firefly's square is far above it (a luminance of 3e9 still fits; the resolution becomes 2^-32).
constexpr int kSquareShift = 32;

// A pass with zero variance is exact; its weight is huge but finite.
double inverse(double variance) { return 1 / std::max(variance, 1e-300); }

}  // namespace

InverseVarianceCombiner::InverseVarianceCombiner(int width, int height)
    : width_(width),
      height_(height),
      current_(size_t(width) * size_t(height) * kSumsPerPixel + 1, 0),
      combined_(size_t(width) * size_t(height), Rgb(0.f)) {}

void InverseVarianceCombiner::add(size_t pixel, Rgb value) {
  if (!value.is_finite()) return;
  FixedSum* m = &current_[pixel * kSumsPerPixel];
  m[0] += to_fixed(value.r);
  m[1] += to_fixed(value.g);
  m[2] += to_fixed(value.b);
  const double y = value.luminance();
  m[3] += to_fixed(std::ldexp(y * y, -kSquareShift));
}

Rgb InverseVarianceCombiner::mean(size_t i, double n) const {
  const FixedSum* m = &current_[i * kSumsPerPixel];
  return Rgb(float(from_fixed(m[0]) / n), float(from_fixed(m[1]) / n), float(from_fixed(m[2]) / n));
}

InverseVarianceCombiner::Pass InverseVarianceCombiner::current_pass() const {
  const uint32_t samples = this->samples();
  if (samples < 2) return {samples, -1, -1};
  const double n = samples;
  const size_t pixels = size_t(width_) * size_t(height_);
  double sum = 0, sum2 = 0;
  for (size_t i = 0; i < pixels; ++i) {
    const FixedSum* m = &current_[i * kSumsPerPixel];
    const double y =
        0.2126 * from_fixed(m[0]) + 0.7152 * from_fixed(m[1]) + 0.0722 * from_fixed(m[2]);
    // Unbiased sample variance of the luminance, over n for the variance of the mean.
    const double y2 = std::ldexp(from_fixed(m[3]), kSquareShift);
    const double v = std::max(0.0, y2 - y * y / n) / (n - 1) / n;
    sum += v;
    sum2 += v * v;
  }
  const double p = double(pixels), mean = sum / p;
  const double spread = pixels > 1 ? std::max(0.0, sum2 / p - mean * mean) * p / (p - 1) : 0.0;
  return {samples, mean, std::sqrt(spread / p)};
}

void InverseVarianceCombiner::end_pass() {
  const Pass pass = current_pass();
  const double v = pass.variance;
  completed_.push_back(pass);
  if (v >= 0) {
    const double w = inverse(v), total = weight_ + w, n = samples();
    for (size_t i = 0; i < combined_.size(); ++i)
      combined_[i] = combined_[i] * float(weight_ / total) + mean(i, n) * float(w / total);
    weight_ = total;
  }
  clear_current();
}

void InverseVarianceCombiner::clear_current() {
  std::fill(current_.begin(), current_.end(), FixedSum(0));
}

Image InverseVarianceCombiner::image() const {
  const double v = current_pass().variance;
  if (v < 0 && weight_ == 0) return Image();
  Image out(width_, height_);
  const double w = v < 0 ? 0 : inverse(v), total = weight_ + w, n = samples();
  for (size_t i = 0; i < combined_.size(); ++i) {
    Rgb c = combined_[i] * float(weight_ / total);
    if (w > 0) c += mean(i, n) * float(w / total);
    out[i] = c;
  }
  return out;
}

std::vector<InverseVarianceCombiner::Pass> InverseVarianceCombiner::passes() const {
  std::vector<Pass> all = completed_;
  if (samples() > 0) all.push_back(current_pass());
  return all;
}

size_t InverseVarianceCombiner::bytes() const {
  return current_.capacity() * sizeof(FixedSum) + combined_.capacity() * sizeof(Rgb);
}

}  // namespace caustica
