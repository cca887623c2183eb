// Conductors: "conductor" (smooth or rough GGX metal, pbrt-v4 ConductorBxDF) and a perfect
// mirror.
//
// conductor  eta          RGB texture  complex IOR, real part (default: pbrt-v4's metal-Cu-eta)
//            k            RGB texture  complex IOR, imaginary part (default metal-Cu-k)
//            reflectance  RGB texture  if given, replaces eta/k: eta = 1,
//                                      k = 2 sqrt(r) / sqrt(1 - r), r clamped to [0, 0.9999]
//                                      (normal-incidence reflectance is then exactly r)
//            uroughness / vroughness   default 0; alpha < 1e-3 gives a delta lobe
//            remaproughness            default true (roughness -> alpha = sqrt)
// mirror     reflectance  RGB          constant reflectance at every angle (1 = lossless)
#include "materials/conductor_bxdf.h"
#include "materials/fresnel.h"
#include "materials/materials.h"
#include "materials/roughness.h"

namespace caustica {
namespace {

// Ideal specular reflection with an angle-independent reflectance.
class MirrorBxDF final : public BxDF {
 public:
  explicit MirrorBxDF(Rgb r) : r_(r) {}
  uint32_t flags() const override { return kBxdfSpecularReflection; }
  Rgb f(Vec3, Vec3, TransportMode) const override { return {}; }
  std::optional<BsdfSample> sample(Vec3 wo, float, Vec2, TransportMode) const override {
    BsdfSample s;
    s.wi = Vec3(-wo.x, -wo.y, wo.z);
    s.f = r_ / abs_cos_theta(s.wi);
    s.pdf = 1;
    s.flags = kBxdfSpecularReflection;
    return s;
  }
  float pdf(Vec3, Vec3, TransportMode) const override { return 0; }

 private:
  Rgb r_;
};

class ConductorMaterial final : public Material {
 public:
  explicit ConductorMaterial(const ConductorParams& p) : p_(p) {}
  Bsdf bsdf(const SurfaceInteraction& si, ScratchArena& arena) const override {
    const TextureContext ctx{si.uv, si.p};
    const TrowbridgeReitz distrib =
        eval_distribution(p_.u_roughness, p_.v_roughness, p_.remap_roughness, ctx);
    Rgb eta, k;
    if (p_.reflectance) {
      // pbrt-v4 ConductorMaterial: the eta = 1 conductor whose normal reflectance is r.
      const Rgb r = clamp(p_.reflectance->eval(ctx), 0.f, 0.9999f);
      eta = Rgb(1.f);
      k = 2.f * sqrt(r) / sqrt(Rgb(1.f) - r);
    } else {
      eta = p_.eta->eval(ctx);
      k = p_.k->eval(ctx);
    }
    return Bsdf(arena.make<ConductorBxDF>(distrib, eta, k), si.shading, si.ng);
  }
  const char* name() const override { return "conductor"; }

 private:
  ConductorParams p_;
};

class MirrorMaterial final : public Material {
 public:
  explicit MirrorMaterial(Rgb r) : r_(r) {}
  Bsdf bsdf(const SurfaceInteraction& si, ScratchArena& arena) const override {
    return Bsdf(arena.make<MirrorBxDF>(r_), si.shading, si.ng);
  }
  const char* name() const override { return "mirror"; }

 private:
  Rgb r_;
};

}  // namespace

MaterialPtr make_conductor(const ConductorParams& params) {
  ConductorParams p = params;
  if (!p.reflectance) {
    // pbrt-v4's defaults are the copper spectra.
    if (!p.eta) p.eta = make_constant_texture(*named_spectrum_rgb("metal-Cu-eta"));
    if (!p.k) p.k = make_constant_texture(*named_spectrum_rgb("metal-Cu-k"));
  }
  return std::make_shared<ConductorMaterial>(p);
}

MaterialPtr make_mirror(Rgb reflectance) { return std::make_shared<MirrorMaterial>(reflectance); }

}  // namespace caustica
