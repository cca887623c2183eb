#include "integrators/bidir/segment_moments.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <utility>

#include "film/film.h"

namespace caustica::bidir {

namespace {
// The film's three channel totals of pixel p, added: 3x the scalar estimate, exactly.
FixedSum channels(std::span<const FixedSum> totals, size_t p) {
  return totals[3 * p] + totals[3 * p + 1] + totals[3 * p + 2];
}
}  // namespace

void SegmentMoments::reset(std::vector<size_t> pixels) {
  pixels_ = std::move(pixels);
  before_.assign(pixels_.size(), 0);
  sums_.assign(2 * pixels_.size() + 1, 0);
}

void SegmentMoments::clear() { std::fill(sums_.begin(), sums_.end(), FixedSum(0)); }

void SegmentMoments::begin_iteration(const Film& film) {
  const std::span<const FixedSum> totals = film.sums();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, before_.size(), 4096), [&](const auto& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) before_[i] = channels(totals, pixels_[i]);
  });
}

void SegmentMoments::end_iteration(const Film& film) {
  const std::span<const FixedSum> totals = film.sums();
  // Each pixel is its own: the split over threads changes no sum.
  tbb::parallel_for(tbb::blocked_range<size_t>(0, before_.size(), 4096), [&](const auto& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const FixedSum v3 = channels(totals, pixels_[i]) - before_[i];
      const double v = from_fixed(v3) / 3.0;
      sums_[2 * i] += v3;
      sums_[2 * i + 1] += to_fixed(v * v);  // clamped at 2^31 (fixed_sum.h)
    }
  });
  sums_.back() += to_fixed(1.0);
}

std::vector<double> SegmentMoments::variances(std::span<const FixedSum> sums, double* iterations) {
  const double m = sums.empty() ? 0.0 : from_fixed(sums.back());
  *iterations = m;
  if (m < 2) return {};
  const size_t pixels = (sums.size() - 1) / 2;
  std::vector<double> out(pixels);
  for (size_t p = 0; p < pixels; ++p) {
    const double mean = from_fixed(sums[2 * p]) / 3.0 / m;
    const double square = from_fixed(sums[2 * p + 1]) / m;
    out[p] = std::max(square - mean * mean, 0.0) * m / (m - 1);
  }
  return out;
}

}  // namespace caustica::bidir
