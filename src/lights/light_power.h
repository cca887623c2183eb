// The power (flux) each light model emits per unit of its emission value, written once for
// two readers: the models' power(), which the light selection distribution is built from, and
// the loaders' "power" parameters (pbrt-v4 scales I or L so that the light emits the given
// power: scale = power / power_per_unit).
#pragma once

namespace caustica {

// Point light: intensity I in every direction of the sphere, Phi = 4 pi I.
float point_light_power_per_intensity();

// Spot light with pbrt-v4's smoothstep falloff, from full intensity at cos_falloff_start down to
// zero at cos_falloff_end: Phi = 2 pi I ((1 - cos_start) + (cos_start - cos_end) / 2).
float spot_light_power_per_intensity(float cos_falloff_start, float cos_falloff_end);

// Diffuse emitter of radiance L over `area`: Phi = pi L area on each emitting side.
float diffuse_area_light_power_per_radiance(float area, bool two_sided);

}  // namespace caustica
