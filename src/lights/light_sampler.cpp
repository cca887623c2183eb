#include "lights/light_sampler.h"

namespace caustica {

LightSampler::LightSampler(const std::vector<const Light*>& lights) : lights_(lights) {
  if (lights_.empty()) return;
  std::vector<float> weights;
  weights.reserve(lights_.size());
  for (const Light* l : lights_) weights.push_back(std::max(0.f, l->power().luminance()));
  distribution_ = Distribution1D(std::move(weights));
}

const Light* LightSampler::sample(float u, float* pmf) const {
  if (lights_.empty()) {
    *pmf = 0;
    return nullptr;
  }
  const size_t i = distribution_.sample_discrete(u, pmf);
  return lights_[i];
}

}  // namespace caustica
