// Lambertian materials: "diffuse" and "diffusetransmission" (pbrt-v4 semantics).
//
// diffuse             reflectance  texture  default 0.5   albedo, clamped to [0, 1]
// diffusetransmission reflectance  texture  default 0.25  albedo of the reflection lobe
//                     transmittance texture default 0.25  albedo of the transmission lobe
//                     scale        float    default 1     multiplies both before clamping
#include "materials/diffuse_bxdf.h"
#include "materials/materials.h"

namespace caustica {
namespace {

// Lambertian reflection on both sides plus Lambertian transmission (pbrt-v4
// DiffuseTransmissionBxDF). Lobes are chosen in proportion to the max channel of R and T.
class DiffuseTransmissionBxDF final : public BxDF {
 public:
  DiffuseTransmissionBxDF(Rgb r, Rgb t) : r_(r), t_(t) {}

  uint32_t flags() const override {
    uint32_t fl = (r_.is_black() ? 0u : kBxdfDiffuseReflection) |
                  (t_.is_black() ? 0u : kBxdfDiffuseTransmission);
    return fl ? fl : uint32_t(kBxdfDiffuseReflection);  // black: see DiffuseBxDF::flags
  }
  Rgb f(Vec3 wo, Vec3 wi, TransportMode) const override {
    return same_hemisphere(wo, wi) ? r_ * kInvPi : t_ * kInvPi;
  }
  std::optional<BsdfSample> sample(Vec3 wo, float uc, Vec2 u, TransportMode mode) const override {
    const float pr = r_.max_component(), pt = t_.max_component();
    if (pr == 0 && pt == 0) return std::nullopt;
    BsdfSample s;
    s.wi = sample_cosine_hemisphere(u);
    if (uc < pr / (pr + pt)) {
      if (wo.z < 0) s.wi.z = -s.wi.z;
      s.pdf = cosine_hemisphere_pdf(abs_cos_theta(s.wi)) * pr / (pr + pt);
      s.flags = kBxdfDiffuseReflection;
    } else {
      if (wo.z > 0) s.wi.z = -s.wi.z;
      s.pdf = cosine_hemisphere_pdf(abs_cos_theta(s.wi)) * pt / (pr + pt);
      s.flags = kBxdfDiffuseTransmission;
    }
    s.f = f(wo, s.wi, mode);
    return s;
  }
  float pdf(Vec3 wo, Vec3 wi, TransportMode) const override {
    const float pr = r_.max_component(), pt = t_.max_component();
    if (pr == 0 && pt == 0) return 0;
    const float p = same_hemisphere(wo, wi) ? pr : pt;
    return p / (pr + pt) * cosine_hemisphere_pdf(abs_cos_theta(wi));
  }

 private:
  Rgb r_, t_;
};

class DiffuseMaterial final : public Material {
 public:
  explicit DiffuseMaterial(TexturePtr reflectance) : reflectance_(std::move(reflectance)) {}
  Bsdf bsdf(const SurfaceInteraction& si, ScratchArena& arena) const override {
    const Rgb r = clamp(reflectance_->eval({si.uv, si.p}), 0.f, 1.f);
    return Bsdf(arena.make<DiffuseBxDF>(r), si.shading, si.ng);
  }
  const char* name() const override { return "diffuse"; }

 private:
  TexturePtr reflectance_;
};

class DiffuseTransmissionMaterial final : public Material {
 public:
  DiffuseTransmissionMaterial(TexturePtr r, TexturePtr t, float scale)
      : reflectance_(std::move(r)), transmittance_(std::move(t)), scale_(scale) {}
  Bsdf bsdf(const SurfaceInteraction& si, ScratchArena& arena) const override {
    const TextureContext ctx{si.uv, si.p};
    const Rgb r = clamp(reflectance_->eval(ctx) * scale_, 0.f, 1.f);
    const Rgb t = clamp(transmittance_->eval(ctx) * scale_, 0.f, 1.f);
    return Bsdf(arena.make<DiffuseTransmissionBxDF>(r, t), si.shading, si.ng);
  }
  const char* name() const override { return "diffusetransmission"; }

 private:
  TexturePtr reflectance_, transmittance_;
  float scale_;
};

}  // namespace

MaterialPtr make_diffuse(TexturePtr reflectance) {
  if (!reflectance) reflectance = make_constant_texture(Rgb(0.5f));
  return std::make_shared<DiffuseMaterial>(std::move(reflectance));
}

MaterialPtr make_diffuse_transmission(TexturePtr reflectance, TexturePtr transmittance,
                                      float scale) {
  if (!reflectance) reflectance = make_constant_texture(Rgb(0.25f));
  if (!transmittance) transmittance = make_constant_texture(Rgb(0.25f));
  return std::make_shared<DiffuseTransmissionMaterial>(std::move(reflectance),
                                                       std::move(transmittance), scale);
}

}  // namespace caustica
