// `pt`: unidirectional path tracing with next event estimation and BSDF sampling combined by
// multiple importance sampling (Veach 1997, ch. 9), Russian roulette, delta BSDFs and lights.
// A camera-path integrator: the seam (camera_path.h) owns pixels, streams and the film.
#pragma once

#include "integrators/camera_path.h"

namespace caustica {

class PathTracer final : public CameraPathIntegrator {
 public:
  explicit PathTracer(const IntegratorSettings& settings)
      : CameraPathIntegrator(settings.seed), settings_(settings) {}
  const char* name() const override { return "pt"; }

  // Radiance arriving along a camera ray; exposed for tests.
  Rgb radiance(const Scene& scene, const Ray& ray, Pcg32& rng, ScratchArena& arena) const;

 protected:
  Rgb estimate(const Scene& scene, const CameraSample& sample, Pcg32& rng, ScratchArena& arena,
               uint64_t*) const override {
    return radiance(scene, sample.ray, rng, arena);
  }

 private:
  IntegratorSettings settings_;
};

}  // namespace caustica
