#include "core/distribution.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace caustica {

// Largest i in [lo, lo + len) with cdf[i] <= u, given cdf[lo] <= u (or lo = 0). A binary
// search whose steps are selects, not branches: no mispredicted branch per halving.
static size_t search_range(const float* cdf, size_t lo, size_t len, float u) {
  while (len > 1) {
    const size_t half = len / 2;
    lo = cdf[lo + half] <= u ? lo + half : lo;
    len -= half;
  }
  return lo;
}

static std::vector<uint32_t> build_guide(const std::vector<float>& cdf) {
  const size_t n = cdf.size() - 1;
  size_t steps = 1;
  while (steps * 4 < n && steps < (size_t(1) << 22)) steps *= 2;
  std::vector<uint32_t> guide(steps + 1);
  size_t i = 0;
  for (size_t k = 0; k <= steps; ++k) {
    // k / steps is exact in float (steps is a power of two), as u * steps is at lookup.
    const float t = float(k) / float(steps);
    while (i + 1 <= n && cdf[i + 1] <= t) ++i;
    guide[k] = uint32_t(i);
  }
  return guide;
}

Distribution1D::Distribution1D(std::vector<float> weights) : func_(std::move(weights)) {
  if (func_.empty()) throw std::invalid_argument("Distribution1D needs at least one weight");
  for (float& f : func_)
    if (!(f > 0) || !std::isfinite(f)) f = 0;
  const size_t n = func_.size();
  cdf_.resize(n + 1);
  cdf_[0] = 0;
  double acc = 0;
  for (size_t i = 0; i < n; ++i) {
    acc += func_[i];
    cdf_[i + 1] = float(acc);
  }
  if (acc == 0) {
    std::fill(func_.begin(), func_.end(), 1.f);
    for (size_t i = 0; i <= n; ++i) cdf_[i] = float(i) / float(n);
    integral_ = 1;
    guide_ = build_guide(cdf_);
    return;
  }
  integral_ = float(acc / double(n));
  for (size_t i = 1; i <= n; ++i) cdf_[i] = float(cdf_[i] / acc);
  cdf_[n] = 1;
  guide_ = build_guide(cdf_);
}

size_t Distribution1D::find_interval(float u) const {
  // Clamped to [0, n-1] (cdf[0] = 0); the same index as std::upper_bound minus one for u >= 0.
  const size_t n = func_.size();
  if (!(u >= 0)) return 0;
  const size_t steps = guide_.size() - 1;
  const float scaled = u * float(steps);  // exact: steps is a power of two
  const size_t k = scaled < float(steps) ? size_t(scaled) : steps - 1;
  // k / steps <= u < (k + 1) / steps (or k is the last step), so the answer lies in
  // [guide_[k], guide_[k + 1]].
  const size_t lo = guide_[k], hi = guide_[k + 1];
  return std::min(search_range(cdf_.data(), lo, hi - lo + 1, u), n - 1);
}

size_t Distribution1D::sample_discrete(float u, float* pmf_out, float* remapped) const {
  size_t i = find_interval(u);
  while (func_[i] == 0 && i + 1 < func_.size()) ++i;  // guard against u landing on a flat step
  if (pmf_out) *pmf_out = pmf(i);
  if (remapped) {
    const float w = cdf_[i + 1] - cdf_[i];
    *remapped = w > 0 ? std::min((u - cdf_[i]) / w, kOneMinusEpsilon) : 0.f;
    *remapped = std::max(*remapped, 0.f);
  }
  return i;
}

float Distribution1D::pmf(size_t i) const {
  return i < func_.size() ? func_[i] / (integral_ * float(func_.size())) : 0.f;
}

float Distribution1D::sample_continuous(float u, float* pdf, size_t* offset) const {
  size_t i = find_interval(u);
  while (func_[i] == 0 && i + 1 < func_.size()) ++i;
  if (offset) *offset = i;
  float du = u - cdf_[i];
  const float w = cdf_[i + 1] - cdf_[i];
  if (w > 0) du /= w;
  du = clamp(du, 0.f, kOneMinusEpsilon);
  if (pdf) *pdf = func_[i] / integral_;
  return std::min((float(i) + du) / float(func_.size()), kOneMinusEpsilon);
}

float Distribution1D::pdf_continuous(float x) const {
  if (!(x >= 0 && x < 1)) return 0;
  const size_t i = std::min(size_t(x * float(func_.size())), func_.size() - 1);
  return func_[i] / integral_;
}

Distribution2D::Distribution2D(const std::vector<float>& values, int width, int height)
    : width_(width), height_(height) {
  if (width <= 0 || height <= 0 || values.size() != size_t(width) * size_t(height))
    throw std::invalid_argument("Distribution2D: size mismatch");
  std::vector<float> marginal(height);
  conditional_.reserve(height);
  for (int v = 0; v < height; ++v) {
    std::vector<float> row(values.begin() + size_t(v) * width,
                           values.begin() + size_t(v + 1) * width);
    double sum = 0;
    for (float f : row) sum += (f > 0 && std::isfinite(f)) ? f : 0.f;
    marginal[v] = float(sum / width);
    conditional_.emplace_back(std::move(row));
  }
  marginal_ = Distribution1D(std::move(marginal));
}

Vec2 Distribution2D::sample(Vec2 u, float* pdf) const {
  float pdf_v, pdf_u;
  size_t v;
  const float y = marginal_.sample_continuous(u.y, &pdf_v, &v);
  const float x = conditional_[v].sample_continuous(u.x, &pdf_u);
  if (pdf) *pdf = pdf_v * pdf_u;
  return {x, y};
}

float Distribution2D::pdf(Vec2 p) const {
  if (!(p.x >= 0 && p.x < 1 && p.y >= 0 && p.y < 1)) return 0;
  const int v = std::min(int(p.y * height_), height_ - 1);
  return marginal_.pdf_continuous(p.y) * conditional_[v].pdf_continuous(p.x);
}

}  // namespace caustica
