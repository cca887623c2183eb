#include "image/inverse_variance.h"

#include <algorithm>
#include <cmath>

namespace caustica {

namespace {

// A pass with zero variance is exact; its weight is huge but finite.
double inverse(double variance) { return 1 / std::max(variance, 1e-300); }

}  // namespace

InverseVarianceCombiner::InverseVarianceCombiner(int width, int height)
    : width_(width),
      height_(height),
      current_(size_t(width) * size_t(height)),
      combined_(size_t(width) * size_t(height), Rgb(0.f)) {}

void InverseVarianceCombiner::add(size_t pixel, Rgb value) {
  if (!value.is_finite()) return;
  Moments& m = current_[pixel];
  m.r += value.r;
  m.g += value.g;
  m.b += value.b;
  const double y = value.luminance();
  m.luminance2 += y * y;
}

double InverseVarianceCombiner::current_variance() const {
  if (samples_ < 2 || current_.empty()) return -1;
  const double n = samples_;
  double sum = 0;
  for (const Moments& m : current_) {
    const double y = 0.2126 * m.r + 0.7152 * m.g + 0.0722 * m.b;
    // Unbiased sample variance of the luminance, over n for the variance of the mean.
    sum += std::max(0.0, m.luminance2 - y * y / n) / (n - 1) / n;
  }
  return sum / double(current_.size());
}

void InverseVarianceCombiner::end_pass() {
  const double v = current_variance();
  completed_.push_back({samples_, v});
  if (v >= 0) {
    const double w = inverse(v), total = weight_ + w, n = samples_;
    for (size_t i = 0; i < current_.size(); ++i) {
      const Moments& m = current_[i];
      const Rgb mean(float(m.r / n), float(m.g / n), float(m.b / n));
      combined_[i] = combined_[i] * float(weight_ / total) + mean * float(w / total);
    }
    weight_ = total;
  }
  std::fill(current_.begin(), current_.end(), Moments{});
  samples_ = 0;
}

Image InverseVarianceCombiner::image() const {
  const double v = current_variance();
  if (v < 0 && weight_ == 0) return Image();
  Image out(width_, height_);
  const double w = v < 0 ? 0 : inverse(v), total = weight_ + w, n = samples_;
  for (size_t i = 0; i < combined_.size(); ++i) {
    Rgb c = combined_[i] * float(weight_ / total);
    if (w > 0) {
      const Moments& m = current_[i];
      c += Rgb(float(m.r / n), float(m.g / n), float(m.b / n)) * float(w / total);
    }
    out[i] = c;
  }
  return out;
}

std::vector<InverseVarianceCombiner::Pass> InverseVarianceCombiner::passes() const {
  std::vector<Pass> all = completed_;
  if (samples_ > 0) all.push_back({samples_, current_variance()});
  return all;
}

size_t InverseVarianceCombiner::bytes() const {
  return current_.capacity() * sizeof(Moments) + combined_.capacity() * sizeof(Rgb);
}

}  // namespace caustica
