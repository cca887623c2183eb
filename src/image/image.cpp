#include "image/image.h"

#include <algorithm>
#include <cmath>

namespace caustica {
namespace {

// Repeat wrap of an integer texel index into [0, n).
int wrap_index(int i, int n) {
  int m = i % n;
  return m < 0 ? m + n : m;
}

}  // namespace

Rgb Image::bilinear_wrap(float s, float t) const {
  if (empty()) return Rgb(0.f);
  // Reduce to [0,1] first so huge coordinates cannot overflow the int conversion below; a
  // non-finite coordinate has no meaningful texel and reads as 0.
  s = std::isfinite(s) ? s - std::floor(s) : 0.f;
  t = std::isfinite(t) ? t - std::floor(t) : 0.f;
  // Texel (x, y) has its centre at ((x + 0.5) / width, (y + 0.5) / height), as in pbrt-v4's
  // Image::Bilerp, so the lookup is exact at texel centres.
  float x = s * float(width_) - 0.5f, y = t * float(height_) - 0.5f;
  float xf = std::floor(x), yf = std::floor(y);
  float dx = x - xf, dy = y - yf;
  int x0 = wrap_index(int(xf), width_), x1 = wrap_index(int(xf) + 1, width_);
  int y0 = wrap_index(int(yf), height_), y1 = wrap_index(int(yf) + 1, height_);
  return (1 - dx) * (1 - dy) * at(x0, y0) + dx * (1 - dy) * at(x1, y0) +
         (1 - dx) * dy * at(x0, y1) + dx * dy * at(x1, y1);
}

Rgb Image::bilinear(float s, float t, Wrap wrap) const {
  if (wrap == Wrap::Repeat) return bilinear_wrap(s, t);
  if (empty()) return Rgb(0.f);
  // Beyond one image width outside, every texel a lookup touches is an edge texel (Clamp) or
  // black (Black): clamping there keeps the int conversion below in range.
  s = std::isfinite(s) ? std::clamp(s, -1.f, 2.f) : 0.f;
  t = std::isfinite(t) ? std::clamp(t, -1.f, 2.f) : 0.f;
  const float x = s * float(width_) - 0.5f, y = t * float(height_) - 0.5f;
  const float xf = std::floor(x), yf = std::floor(y);
  const float dx = x - xf, dy = y - yf;
  auto texel = [&](int xi, int yi) {
    if (wrap == Wrap::Clamp)
      return at(std::clamp(xi, 0, width_ - 1), std::clamp(yi, 0, height_ - 1));
    return xi < 0 || yi < 0 || xi >= width_ || yi >= height_ ? Rgb(0.f) : at(xi, yi);
  };
  const int x0 = int(xf), y0 = int(yf);
  return (1 - dx) * (1 - dy) * texel(x0, y0) + dx * (1 - dy) * texel(x0 + 1, y0) +
         (1 - dx) * dy * texel(x0, y0 + 1) + dx * dy * texel(x0 + 1, y0 + 1);
}

Rgb Image::average() const {
  if (empty()) return Rgb(0.f);
  double sum[3] = {0, 0, 0};
  for (const Rgb& p : pixels_)
    for (int c = 0; c < 3; ++c) sum[c] += p[c];
  double n = double(pixels_.size());
  return Rgb(float(sum[0] / n), float(sum[1] / n), float(sum[2] / n));
}

}  // namespace caustica
