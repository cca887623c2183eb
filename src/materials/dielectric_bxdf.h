// Dielectric interface BxDF, smooth or rough (pbrt-v4 DielectricBxDF). Private to materials/:
// make_dielectric() is the public way to get one; the layered BSDF uses it as its coat.
//
// eta is the IOR below the surface (-z side) over the IOR above it. Rough surfaces use the
// generalised half vector wm = normalize(wo + etap wi) (Walter et al. 2007) with GGX; the
// reflection / transmission lobe is chosen with probability F(wo.wm) / 1 - F. Refracted
// radiance is scaled by 1/etap^2 only in Radiance mode (Veach 1997, sec. 5.2); importance is
// not. eta == 1 is an index-matched interface: light passes straight through (a delta lobe).
#pragma once

#include "materials/bxdf.h"
#include "materials/lobes.h"
#include "materials/microfacet.h"

namespace caustica {

class DielectricBxDF final : public BxDF {
 public:
  DielectricBxDF(float eta, TrowbridgeReitz distrib) : eta_(eta), distrib_(distrib) {}

  uint32_t flags() const override;
  Rgb f(Vec3 wo, Vec3 wi, TransportMode mode) const override;
  std::optional<BsdfSample> sample(Vec3 wo, float uc, Vec2 u, TransportMode mode) const override {
    return sample(wo, uc, u, mode, Lobes::All);
  }
  float pdf(Vec3 wo, Vec3 wi, TransportMode mode) const override {
    return pdf(wo, wi, mode, Lobes::All);
  }

  std::optional<BsdfSample> sample(Vec3 wo, float uc, Vec2 u, TransportMode mode,
                                   Lobes lobes) const;
  float pdf(Vec3 wo, Vec3 wi, TransportMode mode, Lobes lobes) const;

 private:
  float eta_;
  TrowbridgeReitz distrib_;
};

}  // namespace caustica
