// Bump mapping (pbrt-v4's "displacement" on a material): the surface is displaced along its
// shading normal by a float texture d(u, v), and the BSDF of the wrapped material is placed in
// the frame of the displaced surface. From finite differences of d over du = dv = 0.0005 (pbrt-v4's
// step when a ray has no differentials; caustica's rays have none):
//   dp/du' = dp/du + (d(u + du, v) - d(u, v)) / du * n,   likewise dp/dv',
// and the shading normal is cross(dp/du', dp/dv'), on the side of the geometric normal. pbrt-v4
// also adds d * dn/du, which scales both tangents alike on a sphere and is left out here. pbrt-v4
// takes du from the ray's footprint, so its bumps are smoothed over a pixel where these are not.
#include "materials/materials.h"

namespace caustica {
namespace {

class BumpMappedMaterial final : public Material {
 public:
  BumpMappedMaterial(MaterialPtr inner, TexturePtr displacement)
      : inner_(std::move(inner)), displacement_(std::move(displacement)) {}

  Bsdf bsdf(const SurfaceInteraction& si, ScratchArena& arena) const override {
    constexpr float kStep = 0.0005f;
    const float d = displacement_->eval_float({si.uv, si.p});
    const float du = displacement_->eval_float({si.uv + Vec2(kStep, 0.f), si.p + si.dpdu * kStep});
    const float dv = displacement_->eval_float({si.uv + Vec2(0.f, kStep), si.p + si.dpdv * kStep});
    const Vec3 n = si.shading.n;
    SurfaceInteraction bumped = si;
    bumped.dpdu = si.dpdu + n * ((du - d) / kStep);
    bumped.dpdv = si.dpdv + n * ((dv - d) / kStep);
    Vec3 ns = cross(bumped.dpdu, bumped.dpdv);
    const float len = length(ns);
    if (!(len > 0) || !std::isfinite(len)) return inner_->bsdf(si, arena);
    ns = face_forward(ns / len, si.ng);
    bumped.shading = Frame::from_normal_tangent(ns, bumped.dpdu);
    return inner_->bsdf(bumped, arena);
  }
  const char* name() const override { return inner_->name(); }

 private:
  MaterialPtr inner_;
  TexturePtr displacement_;
};

}  // namespace

MaterialPtr make_bump_mapped(MaterialPtr inner, TexturePtr displacement) {
  if (!inner || !displacement || displacement->is_constant()) return inner;
  return std::make_shared<BumpMappedMaterial>(std::move(inner), std::move(displacement));
}

}  // namespace caustica
