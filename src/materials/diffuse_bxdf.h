// Lambertian reflection BxDF (pbrt-v4 DiffuseBxDF). Private to materials/: the public way to
// get one is make_diffuse(); the layered BSDF uses it as its base.
#pragma once

#include "core/frame.h"
#include "core/warp.h"
#include "materials/bxdf.h"
#include "materials/lobes.h"

namespace caustica {

class DiffuseBxDF final : public BxDF {
 public:
  explicit DiffuseBxDF(Rgb reflectance) : r_(reflectance) {}

  // A black diffuse surface keeps its Diffuse flag (pbrt-v4 reports Unset): that keeps
  // is_delta() false, so integrators treat it as the ordinary, non-scattering surface it is.
  uint32_t flags() const override { return kBxdfDiffuseReflection; }
  Rgb f(Vec3 wo, Vec3 wi, TransportMode) const override {
    return same_hemisphere(wo, wi) ? r_ * kInvPi : Rgb();
  }
  std::optional<BsdfSample> sample(Vec3 wo, float uc, Vec2 u, TransportMode mode) const override {
    return sample(wo, uc, u, mode, Lobes::All);
  }
  float pdf(Vec3 wo, Vec3 wi, TransportMode mode) const override {
    return pdf(wo, wi, mode, Lobes::All);
  }

  std::optional<BsdfSample> sample(Vec3 wo, float, Vec2 u, TransportMode, Lobes lobes) const {
    if (!has(lobes, Lobes::Reflection)) return std::nullopt;
    Vec3 wi = sample_cosine_hemisphere(u);
    if (wo.z < 0) wi.z = -wi.z;
    BsdfSample s;
    s.f = r_ * kInvPi;
    s.wi = wi;
    s.pdf = cosine_hemisphere_pdf(abs_cos_theta(wi));
    s.flags = kBxdfDiffuseReflection;
    return s;
  }
  float pdf(Vec3 wo, Vec3 wi, TransportMode, Lobes lobes) const {
    if (!has(lobes, Lobes::Reflection) || !same_hemisphere(wo, wi)) return 0;
    return cosine_hemisphere_pdf(abs_cos_theta(wi));
  }
  bool is_black() const { return r_.is_black(); }

 private:
  Rgb r_;
};

}  // namespace caustica
