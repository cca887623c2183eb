#include "lights/light_power.h"

#include "core/math.h"

namespace caustica {

float point_light_power_per_intensity() { return 4 * kPi; }

// pbrt-v4 SpotLight::Phi. Exact: over the band, smoothstep(t) with t linear in cos theta
// integrates to half the band's width in cos theta (its mean over [0, 1] is 1/2), and the solid
// angle of a cap of half-angle theta is 2 pi (1 - cos theta).
float spot_light_power_per_intensity(float cos_falloff_start, float cos_falloff_end) {
  return 2 * kPi * ((1 - cos_falloff_start) + (cos_falloff_start - cos_falloff_end) / 2);
}

// Lambertian emission: the cosine-weighted hemisphere integrates to pi.
float diffuse_area_light_power_per_radiance(float area, bool two_sided) {
  return area * kPi * (two_sided ? 2.f : 1.f);
}

}  // namespace caustica
