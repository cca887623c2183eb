// Helpers shared by the material tests (materials_test.cpp, layered_materials_test.cpp,
// fresnel_microfacet_test.cpp).
//
// Every BSDF is built through the public factories and evaluated through Bsdf in a shading
// frame whose normal is world +x: glossy peaks then lie near the equator of the (cos theta,
// phi) grids of chi2.h, where the grid resolves angles best.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>

#include "core/arena.h"
#include "core/rng.h"
#include "geometry/interaction.h"
#include "materials/materials.h"

namespace caustica::test {

inline constexpr TransportMode kRadiance = TransportMode::Radiance;
inline constexpr TransportMode kImportance = TransportMode::Importance;
inline constexpr TransportMode kModes[] = {kRadiance, kImportance};

inline const Frame kTilted(Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(1, 0, 0));

inline TexturePtr constant(float v) { return make_constant_texture(Rgb(v)); }
inline TexturePtr constant(Rgb v) { return make_constant_texture(v); }

// A BSDF placed at a test point; owns the arena its BxDF lives in.
struct Surface {
  std::unique_ptr<ScratchArena> arena = std::make_unique<ScratchArena>();
  Bsdf bsdf;
  explicit Surface(const MaterialPtr& material, Vec3 p = Vec3(0.25f, 0.5f, 0.75f),
                   Vec3 wo = Vec3(1, 0, 0)) {
    SurfaceInteraction si;
    si.p = p;
    si.uv = Vec2(0.3f, 0.6f);
    si.shading = kTilted;
    si.ng = kTilted.n;
    si.wo = wo;
    bsdf = material->bsdf(si, *arena);
  }
  // World direction of a local (theta, phi) direction.
  Vec3 dir(float theta_deg, float phi = 0.4f) const {
    const float t = radians(theta_deg);
    return kTilted.to_world(
        Vec3(std::sin(t) * std::cos(phi), std::sin(t) * std::sin(phi), std::cos(t)));
  }
};

// Mean and max of the sample weight f |cos| / pdf (green channel).
struct WeightStats {
  double mean = 0, max = 0;
};
inline WeightStats sample_weights(const Bsdf& bsdf, Vec3 wo, TransportMode mode, int n = 100000,
                                  int channel = 1) {
  Pcg32 rng(3, 11);
  WeightStats st;
  for (int i = 0; i < n; ++i) {
    const float uc = rng.next_float();
    const auto s = bsdf.sample(wo, uc, rng.next_2d(), mode);
    if (!s) continue;
    const double w = s->f[channel] * bsdf.abs_cos(s->wi) / s->pdf;
    st.mean += w;
    st.max = std::max(st.max, w);
  }
  st.mean /= n;
  return st;
}

// A diffuse base under a dielectric coat (the stochastic layered BSDF), roughness not remapped.
inline MaterialPtr coated(float reflectance, float roughness, int max_depth = 10) {
  CoatedDiffuseParams p;
  p.max_depth = max_depth;
  p.reflectance = constant(reflectance);
  p.u_roughness = p.v_roughness = constant(roughness);
  p.remap_roughness = false;
  return make_coated_diffuse(p);
}

}  // namespace caustica::test
