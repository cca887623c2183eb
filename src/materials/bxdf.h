// The BSDF interface, in the local shading frame (z = shading normal).
//
// Conventions (DESIGN.md):
//  * wo points toward the previous vertex of the path being built, wi is the sampled /
//    queried direction; both point away from the surface and are unit length.
//  * f() is the BSDF value without any cosine; integrators multiply by |cos theta_i|.
//  * mode is the quantity the path carries: Radiance for camera paths, Importance for light
//    paths (the adjoint BSDF, Veach 1997 ch. 5). Non-symmetric scattering — refraction's
//    1/eta^2 radiance scaling — depends on it.
//  * pdf() is in solid angle. The reverse pdf of a bounce (needed by bidirectional MIS) is
//    pdf(wi, wo, !mode): the density of sampling wo when arriving from wi.
//  * Delta (specular) lobes: f() and pdf() return 0 for them; sample() returns the discrete
//    lobe probability in `pdf`, and `f` such that f * |cos theta_i| / pdf is the path weight.
#pragma once

#include <cstdint>
#include <optional>

#include "core/rgb.h"
#include "core/vec.h"

namespace caustica {

enum class TransportMode : uint8_t { Radiance, Importance };
inline TransportMode operator!(TransportMode m) {
  return m == TransportMode::Radiance ? TransportMode::Importance : TransportMode::Radiance;
}

enum BxdfFlags : uint32_t {
  kBxdfNone = 0,
  kBxdfReflection = 1u << 0,
  kBxdfTransmission = 1u << 1,
  kBxdfDiffuse = 1u << 2,
  kBxdfGlossy = 1u << 3,
  kBxdfSpecular = 1u << 4,
  kBxdfDiffuseReflection = kBxdfDiffuse | kBxdfReflection,
  kBxdfDiffuseTransmission = kBxdfDiffuse | kBxdfTransmission,
  kBxdfGlossyReflection = kBxdfGlossy | kBxdfReflection,
  kBxdfGlossyTransmission = kBxdfGlossy | kBxdfTransmission,
  kBxdfSpecularReflection = kBxdfSpecular | kBxdfReflection,
  kBxdfSpecularTransmission = kBxdfSpecular | kBxdfTransmission,
  kBxdfAll = kBxdfDiffuse | kBxdfGlossy | kBxdfSpecular | kBxdfReflection | kBxdfTransmission,
};
inline bool is_specular(uint32_t f) { return f & kBxdfSpecular; }
inline bool is_non_specular(uint32_t f) { return f & (kBxdfDiffuse | kBxdfGlossy); }
inline bool is_transmissive(uint32_t f) { return f & kBxdfTransmission; }

struct BsdfSample {
  Rgb f;               // BSDF value for wi (see delta convention above)
  Vec3 wi;             // sampled direction (local frame in BxDF, world frame from Bsdf)
  float pdf = 0;       // solid-angle density, or discrete probability for delta lobes
  uint32_t flags = 0;  // the single lobe that was sampled (BxdfFlags)
  float eta = 1;       // relative IOR crossed (eta_i/eta_t style as pbrt's etap), 1 if none
  bool pdf_is_proportional = false;  // pdf is only an estimate (stochastic layered BSDFs)

  bool is_specular() const { return flags & kBxdfSpecular; }
  bool is_transmission() const { return flags & kBxdfTransmission; }
};

class BxDF {
 public:
  // Arena-allocated, never destroyed: implementations must be trivially destructible.
  virtual uint32_t flags() const = 0;
  virtual Rgb f(Vec3 wo, Vec3 wi, TransportMode mode) const = 0;
  // uc picks a lobe, u picks a direction in it. Returns nothing when sampling fails (e.g.
  // total internal reflection handled by the other lobe, or a direction below the surface).
  virtual std::optional<BsdfSample> sample(Vec3 wo, float uc, Vec2 u, TransportMode mode) const = 0;
  virtual float pdf(Vec3 wo, Vec3 wi, TransportMode mode) const = 0;

  bool is_delta() const { return !is_non_specular(flags()); }
  // f() and pdf() are stochastic estimates, not values (the layered BSDF of coated_diffuse.cpp):
  // only a sample's own weight f |cos| / pdf is exact, so a technique that divides f() by a
  // density of its own (a guided direction, a mixture pdf) must not use this BxDF.
  virtual bool stochastic() const { return false; }
  // f() is 0 whenever wo and wi lie on opposite sides of the shading plane: true of every BxDF
  // without transmission whose f() is a value (Bxdf.ZeroAcrossSurfaceHoldsWhereClaimed in
  // tests/materials_test.cpp checks each). Integrators may then reject such directions before
  // building anything else.
  bool zero_across_surface() const { return !is_transmissive(flags()) && !stochastic(); }

 protected:
  ~BxDF() = default;
};

}  // namespace caustica
