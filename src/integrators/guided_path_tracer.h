// `guided-pt`: path tracing whose directions come from a one-sample MIS mixture of BSDF sampling
// and the incident radiance learned while rendering (Müller et al. 2017, "Practical Path
// Guiding for Efficient Light-Transport Simulation"; the field is guiding/guiding_field.h).
// Next event estimation is kept, and light samples and emitter hits are combined by MIS with the
// mixture's density. A camera-path integrator: the seam (camera_path.h) owns pixels, streams and
// the film; path_vertex.h gives light samples, emitter pdfs and Russian roulette.
//
// Training schedule: iteration i (one sample per pixel) belongs to pass p = floor(log2(i + 1)),
// so pass p covers iterations [2^p - 1, 2^(p+1) - 1): 1, 2, 4, 8, ... samples per pixel, as the
// paper's doubling training iterations. A pass samples with the distribution learned by the
// passes before it and records into the next one; the first pass samples the BSDF alone.
// Learning never stops, so --spp and --time budget training and rendering together.
//
// How training enters the image: every iteration counts with equal weight. Each iteration's
// estimate is unbiased given the distribution it sampled with (learned from earlier iterations
// only), so the average is unbiased throughout; early passes only add their (larger) variance.
//
// Guided only where the BSDF has no delta lobe (flags without Specular: a microfacet lobe that
// pbrt-v4 calls effectively smooth is Specular here too) and is not stochastic (the layered
// BSDF); elsewhere the BSDF alone is sampled, as `pt`.
//
// Determinism: the radiance samples of an iteration are collected per thread, sorted by pixel
// (stably: a pixel's path runs on one thread, in order) and splatted after the iteration, so
// the field and the image do not depend on thread scheduling.
#pragma once

#include <tbb/enumerable_thread_specific.h>

#include <vector>

#include "guiding/guiding_field.h"
#include "integrators/camera_path.h"

namespace caustica {

class GuidedPathTracer final : public CameraPathIntegrator {
 public:
  // Probability of sampling the learned distribution where there is one (Müller et al. 2017
  // use 0.5 as well).
  static constexpr float kGuidedFraction = 0.5f;

  explicit GuidedPathTracer(const IntegratorSettings& settings, const GuidingSettings& guiding = {})
      : CameraPathIntegrator(settings.seed), settings_(settings), guiding_(guiding) {}
  const char* name() const override { return "guided-pt"; }

  void prepare(const Scene& scene, Film& film) override;
  void render_iteration(const Scene& scene, uint32_t iteration, Film& film) override;
  void report(nlohmann::json& stats) const override;

  // The training pass of an iteration: floor(log2(iteration + 1)).
  static int training_pass(uint32_t iteration);
  const GuidingField& field() const { return field_; }

 protected:
  Rgb estimate(const Scene& scene, const CameraSample& sample, Pcg32& rng, ScratchArena& arena,
               uint64_t* nonfinite) const override;

 private:
  struct Record {
    uint64_t pixel;
    uint32_t leaf;
    Vec3 wi;
    float value;
  };
  float mis_weight(float pdf_a, float pdf_b) const;

  IntegratorSettings settings_;
  GuidingSettings guiding_;
  GuidingField field_;
  int pass_ = 0;
  uint64_t recorded_ = 0;
  mutable tbb::enumerable_thread_specific<std::vector<Record>> records_;
  std::vector<Record> merged_;
};

}  // namespace caustica
