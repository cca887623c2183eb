#include "image/false_color.h"

#include <cmath>
#include <stdexcept>

namespace caustica {

Rgb inferno_ramp(float t) {
  // Piecewise-linear through samples of matplotlib's "inferno" (display sRGB).
  static const Rgb stops[] = {{0.001f, 0.000f, 0.014f}, {0.258f, 0.039f, 0.406f},
                              {0.578f, 0.148f, 0.404f}, {0.865f, 0.317f, 0.226f},
                              {0.988f, 0.645f, 0.040f}, {0.988f, 0.998f, 0.645f}};
  constexpr int n = sizeof(stops) / sizeof(stops[0]);
  t = clamp(std::isfinite(t) ? t : 1.f, 0.f, 1.f) * (n - 1);
  const int i = std::min(int(t), n - 2);
  const float f = t - i;
  return stops[i] * (1 - f) + stops[i + 1] * f;
}

Image false_color_rel_error(const Image& img, const Image& ref, float log_min, float log_max,
                            float eps) {
  if (img.width() != ref.width() || img.height() != ref.height())
    throw std::invalid_argument("false_color_rel_error: image sizes differ");
  Image out(img.width(), img.height());
  for (size_t i = 0; i < img.pixel_count(); ++i) {
    float e = 0;
    for (int c = 0; c < 3; ++c) e += sqr(img[i][c] - ref[i][c]) / (sqr(ref[i][c]) + eps);
    e /= 3;
    const float l = e > 0 ? std::log10(e) : log_min;
    out[i] = inferno_ramp((l - log_min) / (log_max - log_min));
  }
  return out;
}

}  // namespace caustica
