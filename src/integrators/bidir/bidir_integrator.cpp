#include "integrators/bidir/bidir_integrator.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>

#include "film/film.h"
#include "integrators/bidir/bidir_core.h"
#include "integrators/schedule_report.h"
#include "scene/scene.h"

namespace caustica {

namespace bidir {

Techniques techniques_of(BidirAlgorithm a) {
  Techniques t;
  switch (a) {
    case BidirAlgorithm::LightTracing:
      t.light_to_camera = t.camera_stops = t.unweighted = true;
      break;
    case BidirAlgorithm::Bpt:
      t.light_to_camera = t.connect = true;
      break;
    case BidirAlgorithm::Ppm:
      t.merge = t.camera_stops = t.unweighted = true;
      break;
    case BidirAlgorithm::Bpm:
      t.merge = true;
      break;
    case BidirAlgorithm::Vcm:
      t.light_to_camera = t.connect = t.merge = true;
      break;
    case BidirAlgorithm::AdaptiveVcm:
      t.light_to_camera = t.connect = t.merge = t.adaptive = true;
      break;
    case BidirAlgorithm::GuidedBpt:
      t.light_to_camera = t.connect = t.guided = true;
      break;
    case BidirAlgorithm::GuidedVcm:
      t.light_to_camera = t.connect = t.merge = t.guided = true;
      break;
  }
  // MIS-weighted light tracing also connects the emission points (lt's unweighted splats leave
  // the directly seen lights to its camera rays).
  t.light_origin = t.light_to_camera && t.connect;
  return t;
}

const char* name_of(BidirAlgorithm a) {
  switch (a) {
    case BidirAlgorithm::LightTracing:
      return "lt";
    case BidirAlgorithm::Bpt:
      return "bpt";
    case BidirAlgorithm::Ppm:
      return "ppm";
    case BidirAlgorithm::Bpm:
      return "bpm";
    case BidirAlgorithm::Vcm:
      return "vcm";
    case BidirAlgorithm::AdaptiveVcm:
      return "adaptive-vcm";
    case BidirAlgorithm::GuidedBpt:
      return "guided-bpt";
    case BidirAlgorithm::GuidedVcm:
      return "guided-vcm";
  }
  return "?";
}

void BidirIntegrator::prepare(const Scene& scene, Film& film) {
  CameraPathIntegrator::prepare(scene, film);
  filter_ = PixelFilter(scene.camera().pixel_filter());
  Vec3 center;
  float scene_radius;
  scene.bounds().bounding_sphere(&center, &scene_radius);
  base_radius_ = settings_.bidir.radius > 0 ? settings_.bidir.radius
                                            : kDefaultRadiusFactor * std::max(scene_radius, 1e-3f);
  light_paths_ = settings_.bidir.light_paths > 0 ? settings_.bidir.light_paths : film.pixel_count();
  if (!settings_.bidir.techniques_dir.empty()) techniques_.reset(film.width(), film.height());
  if (tech_.guided) {
    guiding_.prepare(scene.bounds(), settings_.guiding, film.pixel_count(), budget_spp(),
                     budget_seconds());
    guided_passes_ = InverseVarianceCombiner(film.width(), film.height());
    camera_values_.assign(film.pixel_count(), Rgb(0.f));
    pass_end_seconds_.clear();
    start_ = std::chrono::steady_clock::now();
  }
  if (tech_.adaptive)
    plan_ = AdaptivePlan(film.width(), film.height(), settings_.bidir.measured_costs,
                         settings_.bidir.probe_every_iteration, settings_.bidir.probe_stride,
                         settings_.bidir.force_pixel_mode);
  if (tech_.adaptive && !techniques_.enabled())
    path_tracer_ = std::make_unique<PathTracer>(settings_);
  if (tech_.adaptive) {
    probe_film_.reset(film.pixel_count());
    probe_weight_ = {};
    segment_.reset(plan_.grid_image_pixels());
    segment_thread_seconds_ = 0;
    segment_iterations_ = 0;
  }
}

void BidirIntegrator::render_iteration(const Scene& scene, uint32_t iteration, Film& film) {
  const auto start = std::chrono::steady_clock::now();
  Iteration it;
  it.index = iteration;
  // r_i = r_1 * i^((alpha - 1) / 2), i 1-based (Knaus & Zwicker 2011; Georgiev et al. 2012).
  it.radius = std::max(
      base_radius_ * std::pow(float(iteration + 1), 0.5f * (settings_.bidir.radius_alpha - 1.f)),
      1e-7f);
  if (tech_.adaptive) {
    it.plan = plan_.plan(iteration);
  } else {
    it.plan.light_paths = light_paths_;
    it.plan.connections = settings_.bidir.connections;
  }
  const uint64_t n = it.plan.light_paths;
  MisCounts counts;
  const bool connect = tech_.connect || tech_.light_to_camera;
  counts.emitter = connect ? 1.f : 0.f;
  counts.light_trace = connect ? float(n) : 0.f;
  counts.connect = connect && n > 0 ? float(it.plan.connections) : 0.f;
  // --merge-mis-scale scales the merges' count in the weights only (adaptive-vcm predicts its
  // candidates' variances under the balance heuristic's counts, so it keeps them).
  const float merge_scale = tech_.adaptive ? 1.f : settings_.bidir.merge_mis_scale;
  counts.merge = tech_.merge ? kPi * it.radius * it.radius * float(n) * merge_scale : 0.f;
  it.rules = MisRules(heuristic_, counts);
  // --merge-mis correlation-aware: vcm only (the others keep the balance heuristic's counts).
  if (correlation_aware() && n > 0)
    it.rules.enable_correlation(kPi * it.radius * it.radius, 1.f / float(n));
  it.rules_no_merge = it.rules.with_merging(false);
  it.rules_camera_only = MisRules(heuristic_, {counts.emitter, 0.f, 0.f, 0.f});
  it.rules_probe = it.rules;
  if (it.plan.probe && it.plan.probe_stride > 1) {
    MisCounts probe = counts;
    probe.connect = connect && n > 0 ? float(it.plan.probe_connections) : 0.f;
    probe.merge = tech_.merge ? kPi * it.radius * it.radius * float(n) : 0.f;
    it.rules_probe = MisRules(heuristic_, probe);
  }
  it.merge_normalization = n ? 1.f / (kPi * it.radius * it.radius * float(n)) : 0.f;
  it.light_path_of =
      LightPathAssignment(film.pixel_count(), std::max<uint64_t>(n, 1), iteration, settings_.seed);
  if (tech_.guided) guiding_.begin_iteration(iteration, seconds_since(start_), n);
  probe_ = {};
  probe_recorded_ = {};
  probe_.light_paths = double(n);
  if (it.plan.probe) plan_.begin_probe(it.radius);
  if (path_tracer_ && n == 0 && !it.plan.probe) ++path_tracing_iterations_;
  // Before this iteration adds anything: the film adds estimates to its totals as they come.
  std::vector<float> means_before;
  std::vector<double> measured;  // the variance the last choice showed, per pixel
  double measured_iterations = 0;
  if (it.plan.probe) {
    probe_film_.begin_probe(film);
    means_before = observed_ ? std::move(observed_means_) : pixel_means(film);
    measured = SegmentMoments::variances(
        observed_segment_.empty() ? segment_.sums() : observed_segment_, &measured_iterations);
    segment_.clear();
    observed_segment_.clear();
  } else if (tech_.adaptive) {
    segment_.begin_iteration(film);
  }
  observed_ = false;

  const auto light_start = std::chrono::steady_clock::now();
  size_chunks(n);
  trace_light_paths(scene, it, film);
  const double light_seconds = seconds_since(light_start);
  const bool any_merge = tech_.merge && it.plan.any_merge();
  if (any_merge) {
    const auto grid_start = std::chrono::steady_clock::now();
    grid_.build(vertices_, it.radius);
    grid_seconds_total_ +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - grid_start).count();
  }
  current_ = it;
  const auto camera_start = std::chrono::steady_clock::now();
  trace_camera_paths(scene, iteration, film);
  collect_work();
  camera_seconds_total_ += seconds_since(camera_start);
  if (tech_.guided) {
    guiding_.end_iteration(scene, vertices_);
    // The pass's pixel moments for the schedule: camera estimates plus this iteration's splats.
    for (size_t p = 0; p < camera_values_.size(); ++p)
      guided_passes_.add(p, camera_values_[p] + splat_image_[p]);
    guided_passes_.end_iteration();
    if (guiding_.end_pass_after(iteration, seconds_since(start_), guided_passes_)) {
      guided_passes_.end_pass();
      pass_end_seconds_.push_back(seconds_since(start_));
    }
  }
  probe_.light_vertices = double(vertices_.size());
  probe_.light_rays = double(light_rays_);
  add_counts(work_total_, probe_);
  if (it.plan.probe) {
    probe_film_.end_probe(film);  // every estimate of the probe is in the film's totals now
    // The plan prices the recorded pixels' camera-pass work and the whole light pass.
    ProbeWork work = probe_recorded_;
    work.light_paths = probe_.light_paths;
    work.light_vertices = probe_.light_vertices;
    work.light_rays = probe_.light_rays;
    work.light_seconds = light_chunk_seconds_;
    if (work.light_seconds == 0) work.light_seconds = light_seconds;
    if (work.camera_seconds == 0 && it.plan.probe_stride == 1)
      work.camera_seconds = seconds_since(camera_start);
    plan_.set_budget(std::max(0, budget_spp()), budget_seconds(),
                     seconds_total_ + seconds_since(start));
    plan_.set_times(probe_seconds_total_ + seconds_since(start),
                    segment_thread_seconds_ / double(tbb::this_task_arena::max_concurrency()),
                    segment_iterations_);
    plan_.finish_probe(work, means_before, measured, measured_iterations, segment_thread_seconds_);
    segment_thread_seconds_ = 0;
    segment_iterations_ = 0;
  } else if (tech_.adaptive) {
    segment_.end_iteration(film);
  }

  ++iterations_;
  last_radius_ = it.radius;
  vertices_total_ += vertices_.size();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  seconds_total_ += seconds;
  if (it.plan.probe) probe_seconds_total_ += seconds;
  if (tech_.adaptive && !it.plan.probe) {
    segment_thread_seconds_ += seconds * double(tbb::this_task_arena::max_concurrency());
    ++segment_iterations_;
  }
}

void BidirIntegrator::finish(const Scene& scene, Film& film) {
  if (tech_.guided) guiding_.make_views(scene);
  if (techniques_.enabled())
    technique_files_ = techniques_.write(settings_.bidir.techniques_dir, film.iterations());
}

Image BidirIntegrator::image(const Film& film) const {
  if (tech_.adaptive) {
    probe_weight_ = plan_.probe_weight(pixel_means(film));
    return probe_film_.image(film, uint32_t(plan_.probes()), probe_weight_.weight);
  }
  if (!tech_.guided || !settings_.guiding.inverse_variance) return film.image();
  Image combined = guided_passes_.image();
  return combined.empty() ? film.image() : combined;
}

std::span<FixedSum> BidirIntegrator::sums_over_ranks(bool root) {
  if (tech_.adaptive) {
    if (!root) probe_film_.clear();  // every rank holds every probe whole
    return probe_film_.sums();
  }
  if (!tech_.guided || !settings_.guiding.inverse_variance) return {};  // the film's image
  if (!root && guiding_.teaches()) guided_passes_.clear_current();
  return guided_passes_.current_sums();
}

void BidirIntegrator::report(nlohmann::json& stats) const {
  if (tech_.adaptive) {
    plan_.report(stats);
    stats["adaptive"]["path_tracer_iterations"] = path_tracing_iterations_;
    // The probes' share of the render's time (what the choice costs).
    stats["adaptive"]["probe_seconds"] = probe_seconds_total_;
    stats["adaptive"]["probe_time_fraction"] =
        seconds_total_ > 0 ? probe_seconds_total_ / seconds_total_ : 0.0;
    // The probes' weight in the image (probe_film.h) and the per-iteration relative variances
    // it is the ratio of (the last image() computed).
    stats["adaptive"]["probe_weight"] = probe_weight_.weight;
    stats["adaptive"]["probe_relative_variance"] = probe_weight_.probe_relative_variance;
    stats["adaptive"]["rendered_relative_variance"] = probe_weight_.rendered_relative_variance;
  }
  if (tech_.guided) {
    guiding_.report(stats);
    report_passes(guided_passes_, settings_.guiding.inverse_variance, pass_end_seconds_,
                  seconds_since(start_), stats["guiding"]);
  }
  nlohmann::json b;
  b["algorithm"] = name();
  b["mis"] = heuristic_ == MisHeuristic::Power ? "power" : "balance";
  b["light_paths_per_iteration"] = light_paths_;
  b["light_vertices_per_iteration"] = iterations_ ? double(vertices_total_) / iterations_ : 0.0;
  b["bytes_per_light_vertex"] = sizeof(LightVertex);
  b["light_vertex_buffer_bytes"] = vertices_.capacity() * sizeof(LightVertex);
  b["hash_grid_bytes"] = grid_.memory_bytes();
  if (algorithm_ == BidirAlgorithm::Vcm) {
    b["merge_mis"] = correlation_aware() ? "correlation-aware" : "balance";
    if (correlation_aware())  // the light vertices' tracks (64 bytes each, longer ones pooled)
      b["correlation_track_bytes"] = tracks_.capacity() * sizeof(StoredTrack) +
                                     track_entries_.capacity() * sizeof(CorrelationEntry);
  }
  if (tech_.merge)
    b["hash_grid_build_ms_per_iteration"] =
        iterations_ ? 1e3 * grid_seconds_total_ / iterations_ : 0.0;
  b["radius_initial"] = base_radius_;
  b["radius_last"] = last_radius_;
  b["radius_alpha"] = settings_.bidir.radius_alpha;
  b["ms_per_iteration"] = iterations_ ? 1e3 * seconds_total_ / iterations_ : 0.0;
  b["light_paths_ms_per_iteration"] = iterations_ ? 1e3 * light_seconds_total_ / iterations_ : 0.0;
  b["camera_paths_ms_per_iteration"] =
      iterations_ ? 1e3 * camera_seconds_total_ / iterations_ : 0.0;
  // What an iteration of the core did on average: the counts the cost model of adaptive-vcm
  // prices (adaptive-vcm's iterations rendered by pt's estimator are not counted).
  const uint32_t core_iterations = iterations_ - path_tracing_iterations_;
  const double per = core_iterations ? 1.0 / core_iterations : 0.0;
  b["work_per_iteration"] = {
      {"light_paths", work_total_.light_paths * per},
      {"light_vertices", work_total_.light_vertices * per},
      {"light_rays", work_total_.light_rays * per},
      {"camera_vertices", work_total_.camera_vertices * per},
      {"nondelta_camera_vertices", work_total_.nondelta_camera_vertices * per},
      {"connections", work_total_.connections * per},
      {"merge_queries", work_total_.merge_queries * per},
      {"photons", work_total_.photons * per}};
  if (!technique_files_.empty()) b["technique_images"] = technique_files_;
  stats["bidir"] = b;
}

std::vector<float> BidirIntegrator::pixel_means(const Film& film) {
  if (film.iterations() == 0) return {};
  const Image image = film.image();
  std::vector<float> means(image.pixels().size());
  for (size_t p = 0; p < means.size(); ++p) means[p] = scalar(image.pixels()[p]);
  return means;
}

void BidirIntegrator::size_chunks(uint64_t n) {
  chunk_paths_ = chunk_paths_for(std::max<uint64_t>(n, 1));
  chunk_count_ = n ? (n + chunk_paths_ - 1) / chunk_paths_ : 0;
}

}  // namespace bidir

std::unique_ptr<Integrator> make_bidir_integrator(BidirAlgorithm algorithm,
                                                  const IntegratorSettings& settings) {
  return std::make_unique<bidir::BidirIntegrator>(algorithm, settings);
}

}  // namespace caustica
