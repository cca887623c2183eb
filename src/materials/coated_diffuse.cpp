// "coateddiffuse": a dielectric coat over a Lambertian base, evaluated with pbrt-v4's
// stochastic LayeredBxDF (materials/layered_bxdf.h), so that highlights and colours match
// pbrt-v4 renders.
//
// Parameters (pbrt-v4 names and defaults):
//   reflectance    texture  0.5    albedo of the diffuse base (clamped to [0, 1])
//   uroughness,    texture  0      roughness of the dielectric coat; remapped by sqrt unless
//   vroughness                     remaproughness is false; alpha < 1e-3 is a smooth coat
//   thickness      float    0.01   distance between the interfaces (medium optical depth scale)
//   eta            float    1.5    IOR of the coat
//   albedo         texture  0      single-scattering albedo of the medium between the layers
//   g              texture  0      Henyey-Greenstein asymmetry of that medium
//   maxdepth       int      10     random-walk length
//   nsamples       int      1      random walks averaged per evaluation
#include "materials/dielectric_bxdf.h"
#include "materials/diffuse_bxdf.h"
#include "materials/layered_bxdf.h"
#include "materials/materials.h"
#include "materials/roughness.h"

namespace caustica {
namespace {

using CoatedDiffuseBxDF = LayeredBxDF<DielectricBxDF, DiffuseBxDF>;

class CoatedDiffuseMaterial final : public Material {
 public:
  explicit CoatedDiffuseMaterial(const CoatedDiffuseParams& p) : p_(p) {}
  Bsdf bsdf(const SurfaceInteraction& si, ScratchArena& arena) const override {
    const TextureContext ctx{si.uv, si.p};
    const Rgb r = clamp(p_.reflectance->eval(ctx), 0.f, 1.f);
    const TrowbridgeReitz distrib =
        eval_distribution(p_.u_roughness, p_.v_roughness, p_.remap_roughness, ctx);
    const Rgb albedo = clamp(p_.albedo->eval(ctx), 0.f, 1.f);
    const float g = clamp(p_.g->eval_float(ctx), -1.f, 1.f);
    const float eta = p_.eta > 0 ? p_.eta : 1.f;
    const auto* bxdf =
        arena.make<CoatedDiffuseBxDF>(DielectricBxDF(eta, distrib), DiffuseBxDF(r), p_.thickness,
                                      albedo, g, p_.max_depth, p_.n_samples);
    return Bsdf(bxdf, si.shading, si.ng);
  }
  const char* name() const override { return "coateddiffuse"; }

 private:
  CoatedDiffuseParams p_;
};

}  // namespace

MaterialPtr make_coated_diffuse(const CoatedDiffuseParams& params) {
  CoatedDiffuseParams p = params;
  if (!p.reflectance) p.reflectance = make_constant_texture(Rgb(0.5f));
  if (!p.albedo) p.albedo = make_constant_texture(Rgb(0.f));
  if (!p.g) p.g = make_constant_texture(Rgb(0.f));
  return std::make_shared<CoatedDiffuseMaterial>(p);
}

}  // namespace caustica
