// Factories for every material model. Loaders and built-in scenes construct materials only
// through these functions; the model classes stay private to materials/*.cpp.
//
// Roughness: values are microfacet alpha (GGX / Trowbridge-Reitz) unless `remap_roughness`
// is true, in which case they go through pbrt-v4's RoughnessToAlpha (sqrt). A roughness
// (alpha) below 1e-3 makes the surface perfectly smooth (delta lobes), as in pbrt-v4.
#pragma once

#include <optional>
#include <string_view>

#include "geometry/texture.h"
#include "materials/material.h"

namespace caustica {

// Lambertian reflection.
MaterialPtr make_diffuse(TexturePtr reflectance);

struct ConductorParams {
  // Either complex IOR (eta, k) per RGB channel, or an artist `reflectance` (normal-incidence
  // colour, mapped to an equivalent eta/k as pbrt-v4 does: eta = 1, k = 2 sqrt(r) / sqrt(1 - r)).
  TexturePtr eta, k;                    // used when reflectance is null
  TexturePtr reflectance;               // optional
  TexturePtr u_roughness, v_roughness;  // null = smooth
  bool remap_roughness = true;
};
MaterialPtr make_conductor(const ConductorParams& params);
// Perfect mirror: reflectance 1 for every angle (pbrt's conductor with reflectance 1).
MaterialPtr make_mirror(Rgb reflectance = Rgb(1.f));

struct DielectricParams {
  float eta = 1.5f;                     // interior IOR over exterior IOR
  TexturePtr u_roughness, v_roughness;  // null = smooth
  bool remap_roughness = true;
};
MaterialPtr make_dielectric(const DielectricParams& params);
// Thin dielectric slab (pbrt-v4 "thindielectric"): reflection and straight-through transmission.
MaterialPtr make_thin_dielectric(float eta);

struct CoatedDiffuseParams {
  TexturePtr reflectance;               // diffuse base albedo (default 0.5)
  TexturePtr u_roughness, v_roughness;  // of the dielectric coat (default 0)
  bool remap_roughness = true;
  float thickness = 0.01f;            // coat thickness (pbrt-v4 default)
  float eta = 1.5f;                   // coat IOR
  TexturePtr albedo;                  // medium albedo between the layers (default 0)
  TexturePtr g;                       // HG asymmetry of that medium (default 0)
  int max_depth = 10, n_samples = 1;  // random-walk settings of the stochastic layered BSDF
};
MaterialPtr make_coated_diffuse(const CoatedDiffuseParams& params);

// pbrt-v4 "coatedconductor": a dielectric coat over a conductor (the same stochastic layered
// BSDF); the conductor's eta and k are relative to the coat (divided by interface_eta).
struct CoatedConductorParams {
  TexturePtr interface_u_roughness, interface_v_roughness;  // of the coat (null: smooth)
  float interface_eta = 1.5f;
  float thickness = 0.01f;
  TexturePtr eta, k;       // the conductor's complex IOR (default metal-Cu), unless reflectance
  TexturePtr reflectance;  // optional: eta = 1, k = 2 sqrt(r) / sqrt(1 - r)
  TexturePtr conductor_u_roughness, conductor_v_roughness;  // null: smooth
  bool remap_roughness = true;
  TexturePtr albedo, g;  // the medium between the layers (default 0)
  int max_depth = 10, n_samples = 1;
};
MaterialPtr make_coated_conductor(const CoatedConductorParams& params);

// pbrt-v4 "diffusetransmission": Lambertian reflection and transmission.
MaterialPtr make_diffuse_transmission(TexturePtr reflectance, TexturePtr transmittance,
                                      float scale = 1.f);

// pbrt-v4 "mix": picks a or b per surface point with probability `amount` of b (the choice
// is a deterministic hash of the point, as pbrt-v4 does, so the result is a blend).
MaterialPtr make_mix(MaterialPtr a, MaterialPtr b, TexturePtr amount);

// pbrt-v4's "displacement" (bump mapping, materials/bump_mapped.cpp): inner's BSDF in the frame
// of the surface displaced along its shading normal by the float texture. Returns inner itself
// for a null or constant displacement (no slope) and for a null inner (an interface).
MaterialPtr make_bump_mapped(MaterialPtr inner, TexturePtr displacement);

// RGB of pbrt-v4's built-in named spectra: "metal-Au-eta", "metal-Au-k", "metal-Ag-*",
// "metal-Cu-*", "metal-Al-*", "metal-CuZn-*", "glass-BK7", "glass-BAF10", ... (IORs are
// returned as grey). Nothing if unknown.
std::optional<Rgb> named_spectrum_rgb(std::string_view name);

}  // namespace caustica
