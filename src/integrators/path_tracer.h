// `pt`: unidirectional path tracing with next event estimation and BSDF sampling combined by
// multiple importance sampling (Veach 1997, ch. 9), Russian roulette, delta BSDFs and lights.
#pragma once

#include "core/arena.h"
#include "core/rgb.h"
#include "core/rng.h"
#include "integrators/integrator.h"
#include "film/pixel_filter.h"

namespace caustica {

class PathTracer final : public Integrator {
 public:
  explicit PathTracer(const IntegratorSettings& settings) : settings_(settings) {}
  const char* name() const override { return "pt"; }
  void prepare(const Scene& scene, Film& film) override;
  void render_iteration(const Scene& scene, uint32_t iteration, Film& film) override;

  // Radiance arriving along a camera ray; exposed for tests.
  Rgb radiance(const Scene& scene, const struct Ray& ray, Pcg32& rng, ScratchArena& arena) const;

 private:
  float mis_weight(float pdf_a, float pdf_b) const;
  IntegratorSettings settings_;
  PixelFilter filter_;  // the scene camera's, set by prepare()
};

}  // namespace caustica
