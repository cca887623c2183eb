// "coatedconductor": a dielectric coat over a conductor (pbrt-v4 CoatedConductorMaterial),
// evaluated with the stochastic layered BSDF (materials/layered_bxdf.h) as pbrt-v4 does:
// LayeredBxDF<DielectricBxDF, ConductorBxDF>. The conductor lies in the coat, so its complex
// IOR is taken relative to the coat's: eta / interface.eta and k / interface.eta.
//
// Parameters (pbrt-v4 names and defaults):
//   interface.roughness,   texture  0     roughness of the coat (u/v default to roughness);
//   interface.uroughness,                 remapped by sqrt unless remaproughness is false
//   interface.vroughness
//   interface.eta          float    1.5   IOR of the coat
//   thickness              float    0.01  distance between the interfaces
//   conductor.eta, .k      texture  metal-Cu-eta / metal-Cu-k
//   reflectance            texture  none  replaces conductor.eta/k: eta = 1,
//                                         k = 2 sqrt(r) / sqrt(1 - r), r clamped to [0, 0.9999]
//   conductor.roughness,   texture  0     roughness of the metal
//   conductor.uroughness, conductor.vroughness
//   albedo, g              texture  0     the medium between the layers
//   maxdepth, nsamples     int      10, 1 random-walk settings
#include "materials/conductor_bxdf.h"
#include "materials/dielectric_bxdf.h"
#include "materials/layered_bxdf.h"
#include "materials/materials.h"
#include "materials/roughness.h"

namespace caustica {
namespace {

using CoatedConductorBxDF = LayeredBxDF<DielectricBxDF, ConductorBxDF>;

class CoatedConductorMaterial final : public Material {
 public:
  explicit CoatedConductorMaterial(const CoatedConductorParams& p) : p_(p) {}
  Bsdf bsdf(const SurfaceInteraction& si, ScratchArena& arena) const override {
    const TextureContext ctx{si.uv, si.p};
    const TrowbridgeReitz coat = eval_distribution(
        p_.interface_u_roughness, p_.interface_v_roughness, p_.remap_roughness, ctx);
    const TrowbridgeReitz metal = eval_distribution(
        p_.conductor_u_roughness, p_.conductor_v_roughness, p_.remap_roughness, ctx);
    const float ieta = p_.interface_eta > 0 ? p_.interface_eta : 1.f;
    Rgb eta, k;
    if (p_.reflectance) {
      const Rgb r = clamp(p_.reflectance->eval(ctx), 0.f, 0.9999f);
      eta = Rgb(1.f);
      k = 2.f * sqrt(r) / sqrt(Rgb(1.f) - r);
    } else {
      eta = p_.eta->eval(ctx);
      k = p_.k->eval(ctx);
    }
    eta = eta / ieta;
    k = k / ieta;
    const Rgb albedo = clamp(p_.albedo->eval(ctx), 0.f, 1.f);
    const float g = clamp(p_.g->eval_float(ctx), -1.f, 1.f);
    const auto* bxdf =
        arena.make<CoatedConductorBxDF>(DielectricBxDF(ieta, coat), ConductorBxDF(metal, eta, k),
                                        p_.thickness, albedo, g, p_.max_depth, p_.n_samples);
    return Bsdf(bxdf, si.shading, si.ng);
  }
  const char* name() const override { return "coatedconductor"; }

 private:
  CoatedConductorParams p_;
};

}  // namespace

MaterialPtr make_coated_conductor(const CoatedConductorParams& params) {
  CoatedConductorParams p = params;
  if (!p.reflectance) {
    if (!p.eta) p.eta = make_constant_texture(*named_spectrum_rgb("metal-Cu-eta"));
    if (!p.k) p.k = make_constant_texture(*named_spectrum_rgb("metal-Cu-k"));
  }
  if (!p.albedo) p.albedo = make_constant_texture(Rgb(0.f));
  if (!p.g) p.g = make_constant_texture(Rgb(0.f));
  return std::make_shared<CoatedConductorMaterial>(p);
}

}  // namespace caustica
