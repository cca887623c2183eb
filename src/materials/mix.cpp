// "mix" (pbrt-v4 MixMaterial): at each hit, one of two materials is chosen, b with probability
// `amount`. The choice is a deterministic hash of the hit point and wo, so re-evaluating the
// same hit gives the same material (needed by bidirectional methods) while the image blends.
//
// mix  materials  [a, b]  the two materials (either may be null: an interface)
//      amount     texture default 0.5   probability of b
#include <bit>

#include "core/rng.h"
#include "materials/materials.h"

namespace caustica {
namespace {

float hash_to_unit_float(Vec3 p, Vec3 wo) {
  uint64_t h = 0x6d69786d6174ull;  // "mixmat"
  for (const float v : {p.x, p.y, p.z, wo.x, wo.y, wo.z})
    h = hash_combine(h, std::bit_cast<uint32_t>(v));
  return std::min(kOneMinusEpsilon, float(h >> 40) * 0x1p-24f);
}

class MixMaterial final : public Material {
 public:
  MixMaterial(MaterialPtr a, MaterialPtr b, TexturePtr amount)
      : a_(std::move(a)), b_(std::move(b)), amount_(std::move(amount)) {}

  Bsdf bsdf(const SurfaceInteraction& si, ScratchArena& arena) const override {
    const Material* chosen = choose(si);
    return chosen ? chosen->bsdf(si, arena) : Bsdf();
  }
  const char* name() const override { return "mix"; }

 private:
  const Material* choose(const SurfaceInteraction& si) const {
    const float amount = amount_->eval_float({si.uv, si.p});
    if (amount <= 0) return a_.get();
    if (amount >= 1) return b_.get();
    return amount < hash_to_unit_float(si.p, si.wo) ? a_.get() : b_.get();
  }

  MaterialPtr a_, b_;
  TexturePtr amount_;
};

}  // namespace

MaterialPtr make_mix(MaterialPtr a, MaterialPtr b, TexturePtr amount) {
  if (!amount) amount = make_constant_texture(Rgb(0.5f));
  return std::make_shared<MixMaterial>(std::move(a), std::move(b), std::move(amount));
}

}  // namespace caustica
