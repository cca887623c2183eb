// A BxDF placed at a surface point: converts between world and shading frame and applies the
// shading-normal correction of the adjoint BSDF for light paths (Veach 1997, eq. 5.19):
//   f*(wo, wi) = f(wo, wi) * |wo.ns| |wi.ng| / (|wo.ng| |wi.ns|)   in Importance mode.
// Integrators multiply every f() by |wi . shading normal| (abs_cos), in both modes; with the
// correction above that yields the geometrically correct weight for light paths.
#pragma once

#include <optional>

#include "core/frame.h"
#include "materials/bxdf.h"

namespace caustica {

class Bsdf {
 public:
  Bsdf() = default;
  Bsdf(const BxDF* bxdf, const Frame& shading, Vec3 ng) : bxdf_(bxdf), shading_(shading), ng_(ng) {}

  bool valid() const { return bxdf_ != nullptr; }
  uint32_t flags() const { return bxdf_->flags(); }
  bool is_delta() const { return bxdf_->is_delta(); }
  bool stochastic() const { return bxdf_->stochastic(); }
  bool zero_across_surface() const { return bxdf_->zero_across_surface(); }
  const Frame& shading() const { return shading_; }
  Vec3 ng() const { return ng_; }
  const BxDF* bxdf() const { return bxdf_; }

  // |cos| of a world direction with the shading normal.
  float abs_cos(Vec3 w) const { return abs_dot(w, shading_.n); }

  Rgb f(Vec3 wo, Vec3 wi, TransportMode mode) const {
    const Vec3 lo = shading_.to_local(wo), li = shading_.to_local(wi);
    if (lo.z == 0) return {};
    return bxdf_->f(lo, li, mode) * shading_correction(wo, wi, mode);
  }
  std::optional<BsdfSample> sample(Vec3 wo, float uc, Vec2 u, TransportMode mode) const {
    const Vec3 lo = shading_.to_local(wo);
    if (lo.z == 0) return std::nullopt;
    auto s = bxdf_->sample(lo, uc, u, mode);
    if (!s || s->pdf == 0 || s->wi.z == 0 || !s->f.is_finite()) return std::nullopt;
    s->wi = shading_.to_world(s->wi);
    s->f *= shading_correction(wo, s->wi, mode);
    return s;
  }
  float pdf(Vec3 wo, Vec3 wi, TransportMode mode) const {
    const Vec3 lo = shading_.to_local(wo);
    if (lo.z == 0) return 0;
    return bxdf_->pdf(lo, shading_.to_local(wi), mode);
  }

 private:
  float shading_correction(Vec3 wo, Vec3 wi, TransportMode mode) const {
    if (mode == TransportMode::Radiance) return 1.f;
    const float num = abs_dot(wo, shading_.n) * abs_dot(wi, ng_);
    const float den = abs_dot(wo, ng_) * abs_dot(wi, shading_.n);
    return den > 0 ? num / den : 0.f;
  }

  const BxDF* bxdf_ = nullptr;
  Frame shading_;
  Vec3 ng_;
};

}  // namespace caustica
