// Dielectrics: "dielectric" (smooth or rough glass, pbrt-v4 DielectricBxDF) and
// "thindielectric" (pbrt-v4 ThinDielectricBxDF).
//
// dielectric      eta                        float  default 1.5  interior / exterior IOR
//                 uroughness / vroughness    default 0; alpha < 1e-3 gives delta lobes
//                 remaproughness             default true (roughness -> alpha = sqrt)
// thindielectric  eta                        float  default 1.5  IOR of the thin slab
#include "materials/dielectric_bxdf.h"
#include "materials/fresnel.h"
#include "materials/materials.h"
#include "materials/roughness.h"

namespace caustica {

uint32_t DielectricBxDF::flags() const {
  // pbrt-v4 reports a rough eta == 1 interface as Glossy although it only ever samples a delta
  // transmission; here it is Specular, so that is_delta() agrees with what sample() returns.
  if (eta_ == 1) return kBxdfSpecularTransmission;
  return kBxdfReflection | kBxdfTransmission |
         (distrib_.effectively_smooth() ? kBxdfSpecular : kBxdfGlossy);
}

std::optional<BsdfSample> DielectricBxDF::sample(Vec3 wo, float uc, Vec2 u, TransportMode mode,
                                                 Lobes lobes) const {
  if (eta_ == 1 || distrib_.effectively_smooth()) {
    // Delta reflection and refraction, chosen in proportion to Fresnel.
    const float R = fr_dielectric(cos_theta(wo), eta_), T = 1 - R;
    const float pr = has(lobes, Lobes::Reflection) ? R : 0.f;
    const float pt = has(lobes, Lobes::Transmission) ? T : 0.f;
    if (pr == 0 && pt == 0) return std::nullopt;
    BsdfSample s;
    if (uc < pr / (pr + pt)) {
      s.wi = Vec3(-wo.x, -wo.y, wo.z);
      s.f = Rgb(R / abs_cos_theta(s.wi));
      s.pdf = pr / (pr + pt);
      s.flags = kBxdfSpecularReflection;
      return s;
    }
    float etap;
    if (!refract(wo, Vec3(0, 0, 1), eta_, &etap, &s.wi)) return std::nullopt;
    float ft = T / abs_cos_theta(s.wi);
    if (mode == TransportMode::Radiance) ft /= sqr(etap);
    s.f = Rgb(ft);
    s.pdf = pt / (pr + pt);
    s.flags = kBxdfSpecularTransmission;
    s.eta = etap;
    return s;
  }

  // Rough: sample a visible microfacet normal, then reflect or refract about it.
  const Vec3 wm = distrib_.sample_wm(wo, u);
  const float R = fr_dielectric(dot(wo, wm), eta_), T = 1 - R;
  const float pr = has(lobes, Lobes::Reflection) ? R : 0.f;
  const float pt = has(lobes, Lobes::Transmission) ? T : 0.f;
  if (pr == 0 && pt == 0) return std::nullopt;
  BsdfSample s;
  if (uc < pr / (pr + pt)) {
    s.wi = reflect(wo, wm);
    if (!same_hemisphere(wo, s.wi)) return std::nullopt;
    s.pdf = distrib_.pdf(wo, wm) / (4 * abs_dot(wo, wm)) * pr / (pr + pt);
    s.f = Rgb(distrib_.D(wm) * distrib_.G(wo, s.wi) * R /
              std::abs(4 * cos_theta(s.wi) * cos_theta(wo)));
    s.flags = kBxdfGlossyReflection;
    return s;
  }
  float etap;
  const bool tir = !refract(wo, wm, eta_, &etap, &s.wi);
  if (tir || same_hemisphere(wo, s.wi) || s.wi.z == 0) return std::nullopt;
  // Jacobian of the generalised half vector, d wm / d wi (Walter et al. 2007, eq. 17).
  const float denom = sqr(dot(s.wi, wm) + dot(wo, wm) / etap);
  const float dwm_dwi = abs_dot(s.wi, wm) / denom;
  s.pdf = distrib_.pdf(wo, wm) * dwm_dwi * pt / (pr + pt);
  float ft = T * distrib_.D(wm) * distrib_.G(wo, s.wi) *
             std::abs(dot(s.wi, wm) * dot(wo, wm) / (cos_theta(s.wi) * cos_theta(wo) * denom));
  if (mode == TransportMode::Radiance) ft /= sqr(etap);
  s.f = Rgb(ft);
  s.flags = kBxdfGlossyTransmission;
  s.eta = etap;
  return s;
}

namespace {

// Generalised half vector of (wo, wi) facing +z, and the relative IOR etap (1 for reflection).
// Returns false for degenerate configurations and back-facing microfacets.
bool half_vector(Vec3 wo, Vec3 wi, float eta, Vec3* wm, float* etap) {
  const float cos_o = cos_theta(wo), cos_i = cos_theta(wi);
  if (cos_i == 0 || cos_o == 0) return false;
  const bool reflect = cos_i * cos_o > 0;
  *etap = reflect ? 1.f : (cos_o > 0 ? eta : 1 / eta);
  Vec3 m = wi * *etap + wo;
  if (length_squared(m) == 0) return false;
  m = face_forward(normalize(m), Vec3(0, 0, 1));
  if (dot(m, wi) * cos_i < 0 || dot(m, wo) * cos_o < 0) return false;
  *wm = m;
  return true;
}

}  // namespace

Rgb DielectricBxDF::f(Vec3 wo, Vec3 wi, TransportMode mode) const {
  if (eta_ == 1 || distrib_.effectively_smooth()) return {};
  Vec3 wm;
  float etap;
  if (!half_vector(wo, wi, eta_, &wm, &etap)) return {};
  const float F = fr_dielectric(dot(wo, wm), eta_);
  const float cos_o = cos_theta(wo), cos_i = cos_theta(wi);
  if (cos_i * cos_o > 0)
    return Rgb(distrib_.D(wm) * distrib_.G(wo, wi) * F / std::abs(4 * cos_i * cos_o));
  const float denom = sqr(dot(wi, wm) + dot(wo, wm) / etap) * cos_i * cos_o;
  float ft =
      distrib_.D(wm) * (1 - F) * distrib_.G(wo, wi) * std::abs(dot(wi, wm) * dot(wo, wm) / denom);
  if (mode == TransportMode::Radiance) ft /= sqr(etap);
  return Rgb(ft);
}

float DielectricBxDF::pdf(Vec3 wo, Vec3 wi, TransportMode, Lobes lobes) const {
  if (eta_ == 1 || distrib_.effectively_smooth()) return 0;
  Vec3 wm;
  float etap;
  if (!half_vector(wo, wi, eta_, &wm, &etap)) return 0;
  const float R = fr_dielectric(dot(wo, wm), eta_), T = 1 - R;
  const float pr = has(lobes, Lobes::Reflection) ? R : 0.f;
  const float pt = has(lobes, Lobes::Transmission) ? T : 0.f;
  if (pr == 0 && pt == 0) return 0;
  if (same_hemisphere(wo, wi)) return distrib_.pdf(wo, wm) / (4 * abs_dot(wo, wm)) * pr / (pr + pt);
  const float denom = sqr(dot(wi, wm) + dot(wo, wm) / etap);
  return distrib_.pdf(wo, wm) * abs_dot(wi, wm) / denom * pt / (pr + pt);
}

namespace {

// A thin slab: reflection and straight-through transmission with the slab's inter-reflections
// summed in closed form (R' = R + T^2 R / (1 - R^2)). Both lobes are delta; no IOR is crossed.
class ThinDielectricBxDF final : public BxDF {
 public:
  explicit ThinDielectricBxDF(float eta) : eta_(eta) {}
  uint32_t flags() const override { return kBxdfReflection | kBxdfTransmission | kBxdfSpecular; }
  Rgb f(Vec3, Vec3, TransportMode) const override { return {}; }
  float pdf(Vec3, Vec3, TransportMode) const override { return 0; }
  std::optional<BsdfSample> sample(Vec3 wo, float uc, Vec2, TransportMode) const override {
    float R = fr_dielectric(abs_cos_theta(wo), eta_), T = 1 - R;
    if (R < 1) {
      R += sqr(T) * R / (1 - sqr(R));
      T = 1 - R;
    }
    BsdfSample s;
    if (uc < R / (R + T)) {
      s.wi = Vec3(-wo.x, -wo.y, wo.z);
      s.f = Rgb(R / abs_cos_theta(s.wi));
      s.pdf = R / (R + T);
      s.flags = kBxdfSpecularReflection;
    } else {
      s.wi = -wo;
      s.f = Rgb(T / abs_cos_theta(s.wi));
      s.pdf = T / (R + T);
      s.flags = kBxdfSpecularTransmission;
    }
    return s;
  }

 private:
  float eta_;
};

class DielectricMaterial final : public Material {
 public:
  explicit DielectricMaterial(const DielectricParams& p) : p_(p) {}
  Bsdf bsdf(const SurfaceInteraction& si, ScratchArena& arena) const override {
    const TextureContext ctx{si.uv, si.p};
    const TrowbridgeReitz distrib =
        eval_distribution(p_.u_roughness, p_.v_roughness, p_.remap_roughness, ctx);
    return Bsdf(arena.make<DielectricBxDF>(p_.eta, distrib), si.shading, si.ng);
  }
  const char* name() const override { return "dielectric"; }

 private:
  DielectricParams p_;
};

class ThinDielectricMaterial final : public Material {
 public:
  explicit ThinDielectricMaterial(float eta) : eta_(eta) {}
  Bsdf bsdf(const SurfaceInteraction& si, ScratchArena& arena) const override {
    return Bsdf(arena.make<ThinDielectricBxDF>(eta_), si.shading, si.ng);
  }
  const char* name() const override { return "thindielectric"; }

 private:
  float eta_;
};

}  // namespace

MaterialPtr make_dielectric(const DielectricParams& params) {
  DielectricParams p = params;
  if (!(p.eta > 0)) p.eta = 1;  // pbrt-v4 treats a zero eta as index-matched
  return std::make_shared<DielectricMaterial>(p);
}

MaterialPtr make_thin_dielectric(float eta) {
  return std::make_shared<ThinDielectricMaterial>(eta > 0 ? eta : 1.f);
}

}  // namespace caustica
