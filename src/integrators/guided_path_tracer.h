// `guided-pt`: path tracing whose directions come from a one-sample MIS mixture of BSDF sampling
// and the incident radiance learned while rendering (Müller et al. 2017, "Practical Path
// Guiding for Efficient Light-Transport Simulation", with the improvements of Müller 2019,
// "Practical Path Guiding in Production"; the field is guiding/guiding_field.h). Next event
// estimation is kept; light samples and emitter hits are combined by MIS with the mixture's
// density. A camera-path integrator: the seam (camera_path.h) owns pixels, streams and the film;
// path_vertex.h gives light samples, emitter pdfs and Russian roulette.
//
// The mixture at a vertex of spatial leaf l: p(w) = a p_bsdf(w) + (1 - a) p_guide(w), with a the
// leaf's BSDF selection probability, learned by Adam (selection_optimizer.h) unless
// --guiding-bsdf-fraction fixes it. Its density is used for the sampled direction's weight, the
// emitter-hit MIS and the next-event MIS alike. Guided only where the BSDF has no delta lobe
// (flags without Specular: a microfacet lobe that pbrt-v4 calls effectively smooth is Specular
// here too) and is not stochastic (the layered BSDF); elsewhere the BSDF alone is sampled, as
// `pt`, and nothing is recorded.
//
// What is learned: at every guided vertex, the radiance arriving along the sampled direction
// (every later contribution divided by the throughput up to and including the vertex, emitter
// hits with their MIS weight) over its density, and the next event sample's radiance times its
// MIS weight over the light density, along the light's direction: together an MIS estimate of
// the incident radiance's integral over each quadrant. Vertices whose estimate is zero are not
// recorded (as Müller's implementation), but every guided vertex counts for the split rule.
// The selection probability learns from the path records only: its target is what direction
// sampling itself contributes (indirect light and its MIS share of direct light), not what next
// event estimation already samples well. Filtered splatting: guiding_settings.h.
//
// Russian roulette runs on the larger of the throughput and the throughput BSDF sampling alone
// would have had (throughput roulette ends guided paths toward bright light for their small
// weight, which is exactly what guiding found).
//
// Training schedule (guiding/training_schedule.h): passes of 1, 2, 4, 8, ... samples per pixel,
// as the paper's doubling training iterations. A pass samples with the distribution learned by
// the passes before it and records into the next one; the first pass samples the BSDF alone.
// The final pass, chosen from the --spp or --time budget and the passes' variances (Müller et
// al. 2017, sec. 5.2), records nothing (no records, sorting or splatting: it costs what
// sampling the mixture costs) and lasts until the budget is spent. --spp and --time budget
// training and rendering together.
//
// How training enters the image: every pass is an unbiased estimate of the image (it samples
// with a distribution learned from earlier passes only). The image combines the passes
// weighted by the inverse of their variance (image/inverse_variance.h, Müller 2019): the early,
// noisy passes count little, and no sample is thrown away. A pass with one sample per pixel has
// no variance estimate and weight 0 (with two iterations or fewer, the plain average is shown).
// With --guiding-combine equal every iteration counts the same (unbiased; the film's average).
// So does a time budget whose trial switched guiding off: the rest is pt's estimator into the
// film alone, as fast as `pt` (the passes' exact per-sample moments cost a few percent of a
// cornell-glass iteration), and its few training iterations count as much as the others.
//
// Memory: a training iteration keeps its records until they are splatted; when they would
// exceed kMaxRecords, the next iteration records one pixel in k (every pixel in turn), each
// record standing for k (its values and vertex counts times k), so the buffers do not grow
// with the resolution.
//
// Determinism: records carry the key (pixel, position along the path) and are gathered in key
// order (pixel_records.h); the field splats each spatial leaf's records in that order after the
// iteration, so the field and the image do not depend on thread scheduling.
#pragma once

#include <tbb/enumerable_thread_specific.h>

#include <chrono>
#include <nlohmann/json.hpp>
#include <vector>

#include "guiding/guiding_field.h"
#include "guiding/pixel_records.h"
#include "guiding/training_schedule.h"
#include "image/inverse_variance.h"
#include "integrators/camera_path.h"
#include "integrators/path_tracer.h"

namespace caustica {

class GuidedPathTracer final : public CameraPathIntegrator {
 public:
  explicit GuidedPathTracer(const IntegratorSettings& settings)
      : CameraPathIntegrator(settings.seed), settings_(settings), unguided_(settings) {}
  const char* name() const override { return "guided-pt"; }

  void prepare(const Scene& scene, Film& film) override;
  void render_iteration(const Scene& scene, uint32_t iteration, Film& film) override;
  Image image(const Film& film) const override;
  void finish(const Scene& scene, Film& film) override;
  void report(nlohmann::json& stats) const override;
  // Training and trial passes teach: every MPI rank renders them (at a fixed --spp every rank
  // then learns the same field and takes the same decisions). Only the final pass is split.
  bool shared_iteration(uint32_t) const override { return !schedule_.final_pass(); }
  // The final pass's pixel moments are summed over the ranks, so that rank 0 combines the passes
  // as one process does.
  std::span<FixedSum> sums_over_ranks(bool root) override;

  const GuidingField& field() const { return field_; }
  const TrainingSchedule& schedule() const { return schedule_; }

 protected:
  Rgb estimate(const Scene& scene, const CameraSample& sample, Pcg32& rng, ScratchArena& arena,
               uint64_t* nonfinite) const override;

 private:
  double seconds_since_start() const;
  // After iteration i: when the next one starts a new pass, the schedule weighs the pass that
  // ended, the field learns what it recorded, and the combiner folds it (at the end of a pass,
  // not the start of the next, so that shared_iteration() knows what the next one does).
  void end_pass_after(uint32_t iteration);
  // The image is the film's average, and the current pass needs no moments: --guiding-combine
  // equal, or the unguided rendering pass after a lost trial.
  bool film_is_the_image() const;

  IntegratorSettings settings_;
  PathTracer unguided_;  // renders when guiding did not pay (with --time: the schedule's trials)
  GuidingField field_;
  TrainingSchedule schedule_;
  std::chrono::steady_clock::time_point start_;  // prepare(): time budgets
  uint64_t recorded_ = 0;
  size_t peak_record_bytes_ = 0;
  // Records per training iteration are kept near this (40 MiB at 40 bytes; the field's copy
  // grouped by leaf doubles it): one pixel in record_stride_ records, its records weighted by the
  // stride (pixel + iteration ≡ 0 mod stride, so every pixel takes its turn). The first iteration
  // guesses kFirstRecordsPerPixel (mirror-caustic makes about 14 at 320x240, cornell-box 6).
  static constexpr size_t kMaxRecords = size_t(1) << 20;
  static constexpr size_t kFirstRecordsPerPixel = 8;
  uint64_t record_stride_ = 1;
  PixelRecords records_;
  // Path vertices per spatial leaf, per thread (added to the field after each iteration).
  mutable tbb::enumerable_thread_specific<std::vector<uint32_t>> vertex_counts_;
  // Per thread and leaf: next event samples taken and of them seeing light (learning pixels).
  mutable tbb::enumerable_thread_specific<std::vector<uint32_t>> nee_counts_;
  nlohmann::json views_;  // what was learned at a few pixels (guide_views.h), by finish()
  // Written by estimate(): one writer per pixel at a time.
  mutable InverseVarianceCombiner passes_;
  std::vector<double> pass_end_seconds_;  // when each completed pass ended (statistics)
  uint32_t iterations_ = 0;               // rendered so far (statistics)
};

}  // namespace caustica
