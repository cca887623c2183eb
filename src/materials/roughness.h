// Roughness textures -> microfacet distribution, as pbrt-v4's materials do (private).
#pragma once

#include "geometry/texture.h"
#include "materials/microfacet.h"

namespace caustica {

// Null textures mean roughness 0 (smooth). With `remap`, values go through RoughnessToAlpha.
inline TrowbridgeReitz eval_distribution(const TexturePtr& u_roughness,
                                         const TexturePtr& v_roughness, bool remap,
                                         const TextureContext& ctx) {
  float u = u_roughness ? u_roughness->eval_float(ctx) : 0.f;
  float v = v_roughness ? v_roughness->eval_float(ctx) : u;
  if (remap) {
    u = TrowbridgeReitz::roughness_to_alpha(u);
    v = TrowbridgeReitz::roughness_to_alpha(v);
  }
  return TrowbridgeReitz(std::max(u, 0.f), std::max(v, 0.f));
}

}  // namespace caustica
