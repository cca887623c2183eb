#include "image/tonemap.h"

#include <cmath>

namespace caustica {
namespace {

float display_value(float linear, float gain) {
  float v = linear * gain;
  if (std::isnan(v)) return 0.f;  // A NaN pixel shows as black instead of poisoning the PNG.
  return linear_to_srgb(clamp(v, 0.f, 1.f));
}

}  // namespace

Image tonemap_srgb(const Image& linear, float exposure_stops) {
  const float gain = std::exp2(exposure_stops);
  Image display(linear.width(), linear.height());
  for (size_t i = 0; i < linear.pixel_count(); ++i) {
    const Rgb& p = linear[i];
    display[i] = Rgb(display_value(p.r, gain), display_value(p.g, gain), display_value(p.b, gain));
  }
  return display;
}

}  // namespace caustica
