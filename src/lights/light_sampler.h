// One light distribution for the whole renderer: lights are picked proportionally to their
// power (luminance of power()), by NEE, by light-subpath emission, and in MIS pdfs alike.
#pragma once

#include <vector>

#include "core/distribution.h"
#include "lights/light.h"

namespace caustica {

class LightSampler {
 public:
  LightSampler() = default;
  explicit LightSampler(const std::vector<const Light*>& lights);

  bool empty() const { return lights_.empty(); }
  // Picks a light; *pmf is its selection probability. Returns nullptr if there are none.
  const Light* sample(float u, float* pmf) const;
  float pmf(const Light* light) const {
    return lights_.empty() ? 0.f : distribution_.pmf(light->index);
  }

 private:
  std::vector<const Light*> lights_;
  Distribution1D distribution_;
};

}  // namespace caustica
