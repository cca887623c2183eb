// Conductor BxDF, smooth or rough GGX (pbrt-v4 ConductorBxDF): Fresnel reflection of a metal
// with complex IOR eta + i k relative to the medium above it. Private to materials/:
// make_conductor() is the public way to get one; the coated conductor uses it as its base
// (with eta and k divided by the coat's IOR, as pbrt-v4 does).
#pragma once

#include "materials/bxdf.h"
#include "materials/fresnel.h"
#include "materials/lobes.h"
#include "materials/microfacet.h"

namespace caustica {

class ConductorBxDF final : public BxDF {
 public:
  ConductorBxDF(TrowbridgeReitz distrib, Rgb eta, Rgb k) : distrib_(distrib), eta_(eta), k_(k) {}

  uint32_t flags() const override {
    return distrib_.effectively_smooth() ? kBxdfSpecularReflection : kBxdfGlossyReflection;
  }

  Rgb f(Vec3 wo, Vec3 wi, TransportMode) const override {
    if (!same_hemisphere(wo, wi) || distrib_.effectively_smooth()) return {};
    const float cos_o = abs_cos_theta(wo), cos_i = abs_cos_theta(wi);
    if (cos_i == 0 || cos_o == 0) return {};
    Vec3 wm = wi + wo;
    if (length_squared(wm) == 0) return {};
    wm = normalize(wm);
    const Rgb F = fr_complex(abs_dot(wo, wm), eta_, k_);
    return F * (distrib_.D(wm) * distrib_.G(wo, wi) / (4 * cos_i * cos_o));
  }

  std::optional<BsdfSample> sample(Vec3 wo, float uc, Vec2 u, TransportMode mode) const override {
    return sample(wo, uc, u, mode, Lobes::All);
  }
  float pdf(Vec3 wo, Vec3 wi, TransportMode mode) const override {
    return pdf(wo, wi, mode, Lobes::All);
  }

  // Restricted to `lobes` (the layered BSDF asks its interfaces for one kind): a conductor only
  // reflects.
  std::optional<BsdfSample> sample(Vec3 wo, float, Vec2 u, TransportMode mode, Lobes lobes) const {
    if (!has(lobes, Lobes::Reflection)) return std::nullopt;
    BsdfSample s;
    if (distrib_.effectively_smooth()) {
      s.wi = Vec3(-wo.x, -wo.y, wo.z);
      s.f = fr_complex(abs_cos_theta(s.wi), eta_, k_) / abs_cos_theta(s.wi);
      s.pdf = 1;
      s.flags = kBxdfSpecularReflection;
      return s;
    }
    if (wo.z == 0) return std::nullopt;
    const Vec3 wm = distrib_.sample_wm(wo, u);
    s.wi = reflect(wo, wm);
    if (!same_hemisphere(wo, s.wi)) return std::nullopt;
    s.pdf = distrib_.pdf(wo, wm) / (4 * abs_dot(wo, wm));
    s.f = f(wo, s.wi, mode);
    s.flags = kBxdfGlossyReflection;
    return s;
  }

  float pdf(Vec3 wo, Vec3 wi, TransportMode, Lobes lobes) const {
    if (!has(lobes, Lobes::Reflection) || !same_hemisphere(wo, wi) || distrib_.effectively_smooth())
      return 0;
    Vec3 wm = wo + wi;
    if (length_squared(wm) == 0) return 0;
    wm = face_forward(normalize(wm), Vec3(0, 0, 1));
    return distrib_.pdf(wo, wm) / (4 * abs_dot(wo, wm));
  }

 private:
  TrowbridgeReitz distrib_;
  Rgb eta_, k_;
};

}  // namespace caustica
