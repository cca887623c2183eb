#include "integrators/bidir/bidir_integrator.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <vector>

#include "core/arena.h"
#include "core/rng.h"
#include "film/film.h"
#include "film/pixel_filter.h"
#include "image/image_io.h"
#include "integrators/bidir/adaptive_plan.h"
#include "integrators/bidir/hash_grid.h"
#include "integrators/bidir/light_path_assignment.h"
#include "integrators/bidir/light_vertex.h"
#include "integrators/bidir/technique_images.h"
#include "integrators/bidir/techniques.h"
#include "integrators/camera_path.h"
#include "integrators/path_vertex.h"
#include "lights/light.h"
#include "lights/light_sampler.h"
#include "materials/material.h"
#include "scene/scene.h"

namespace caustica {

namespace {

using Clock = std::chrono::steady_clock;
using bidir::HashGrid;
using bidir::LightVertex;
using bidir::LightVertexData;
using bidir::MisRules;
using bidir::MisSums;
using bidir::TechniqueImages;

// Light paths per chunk: at most 1024, fewer when that would leave fewer than 64 chunks (a small
// image has few light paths; 4 chunks of 1024 kept 2 threads half idle at 64x64). It depends on
// the path count only, never on the threads, and the vertices and splats are concatenated in
// path order whatever the chunk size: the images do not depend on it.
constexpr uint64_t kMaxChunkPaths = 1024, kMinChunkPaths = 64, kMinChunks = 64;
uint64_t chunk_paths_for(uint64_t light_paths) {
  return std::clamp((light_paths + kMinChunks - 1) / kMinChunks, kMinChunkPaths, kMaxChunkPaths);
}
constexpr float kDefaultRadiusFactor = 0.003f;

// Which techniques take part (tech. rep. section 6, SmallVCM's switches).
struct Techniques {
  bool light_to_camera = false;  // t = 1 splats
  bool connect = false;          // NEE, emitter hits and connections, MIS-weighted
  bool merge = false;            // vertex merging
  bool camera_stops = false;     // camera subpaths end at their first non-delta vertex
  bool unweighted = false;       // single-technique estimators (lt, ppm): all weights 1
  bool adaptive = false;         // configuration chosen per iteration (adaptive_plan.h)
};

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
  }
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
  }
  return "?";
}

struct Splat {
  uint32_t pixel;
  uint32_t technique;
  Rgb value;
};

// Scalar of a contribution for the adaptive plan's moments.
float scalar(Rgb v) { return (v.r + v.g + v.b) * (1.f / 3.f); }

// What one chunk of light paths leaves behind.
struct LightChunk {
  uint64_t first_path = 0;
  std::vector<LightVertex> vertices;
  std::vector<uint32_t> path_ends;  // per path: vertices.size() after it
  std::vector<Splat> splats;
  std::vector<bidir::TechniqueTerms> splat_terms;  // probe iterations: each splat's MIS terms
  uint64_t nonfinite = 0;
  double seconds = 0;  // probe iterations: time spent tracing the chunk
};

// Per-iteration constants.
struct Iteration {
  uint32_t index = 0;
  bidir::IterationPlan plan;  // light paths, connections, merging
  float radius = 0;
  MisRules rules{MisHeuristic::Balance, false, false, 1, 0};
  MisRules rules_no_merge = rules;           // in pixels that do not merge (adaptive-vcm)
  float merge_normalization = 0;             // 1 / (N pi r^2)
  bidir::LightPathAssignment light_path_of;  // pixel -> the light subpath it connects to
};

// A value added to the pixel and, if technique images are kept, to its technique.
struct PixelAccumulator {
  Rgb sum;
  TechniqueImages* techniques = nullptr;
  size_t pixel = 0;
  uint64_t nonfinite = 0;
  float filter_weight = 1;  // the camera sample's pixel-filter weight (pixel_filter.h)
  // Probe iterations of adaptive-vcm: each contribution with its MIS terms, and the work.
  bidir::AdaptivePlan* plan = nullptr;
  bidir::AdaptivePlan::CandidateSums candidate_sums;
  const MisRules* rules = nullptr;
  float radius = 0;
  bidir::ProbeWork work;
  // sum is the estimate before the filter weight (the seam applies it); technique images get
  // each value already weighted, so that they add up to the image. terms: the value's MIS
  // terms (nullptr: a path only one technique makes).
  void add(bool merge, int s, int t, Rgb value, const bidir::TechniqueTerms* terms = nullptr) {
    if (!value.is_finite()) {
      ++nonfinite;
      return;
    }
    sum += value;
    if (techniques)
      techniques->add(TechniqueImages::key(merge, s, t), pixel, value * filter_weight);
    if (plan)
      plan->add(candidate_sums, scalar(value * filter_weight), terms, rules->counts(), radius);
  }
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Ray ray_leaving_light(const LightLeSample& le, const Light& light) {
  if (light.type() == LightType::Area) {
    // The emission point lies on the light's surface: nudge it to the emitting side.
    const Vec3 side = face_forward(le.n, le.dir);
    const float eps = 1e-4f * std::max(1.f, max_component(abs(le.p)));
    return {le.p + side * eps, le.dir, kInfinity};
  }
  return {le.p, le.dir, kInfinity};
}

class BidirIntegrator final : public CameraPathIntegrator {
 public:
  BidirIntegrator(BidirAlgorithm algorithm, const IntegratorSettings& settings)
      : CameraPathIntegrator(hash_combine(settings.seed, 0xca3e7aull)),
        algorithm_(algorithm),
        tech_(techniques_of(algorithm)),
        settings_(settings) {
    heuristic_ = settings.mis_or(MisHeuristic::Balance);
  }
  const char* name() const override { return name_of(algorithm_); }

  void prepare(const Scene& scene, Film& film) override {
    CameraPathIntegrator::prepare(scene, film);
    filter_ = PixelFilter(scene.camera().pixel_filter());
    Vec3 center;
    float scene_radius;
    scene.bounds().bounding_sphere(&center, &scene_radius);
    base_radius_ = settings_.bidir.radius > 0
                       ? settings_.bidir.radius
                       : kDefaultRadiusFactor * std::max(scene_radius, 1e-3f);
    light_paths_ =
        settings_.bidir.light_paths > 0 ? settings_.bidir.light_paths : film.pixel_count();
    if (!settings_.bidir.techniques_dir.empty()) techniques_.reset(film.width(), film.height());
    if (tech_.adaptive)
      plan_ = bidir::AdaptivePlan(film.width(), film.height(), settings_.bidir.measured_costs,
                                  settings_.bidir.probe_every_iteration);
  }

  void render_iteration(const Scene& scene, uint32_t iteration, Film& film) override {
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
    bidir::MisCounts counts;
    const bool connect = tech_.connect || tech_.light_to_camera;
    counts.emitter = connect ? 1.f : 0.f;
    counts.light_trace = connect ? float(n) : 0.f;
    counts.connect = connect && n > 0 ? float(it.plan.connections) : 0.f;
    counts.merge = tech_.merge ? kPi * it.radius * it.radius * float(n) : 0.f;
    it.rules = MisRules(heuristic_, counts);
    it.rules_no_merge = it.rules.with_merging(false);
    it.merge_normalization = n ? 1.f / (kPi * it.radius * it.radius * float(n)) : 0.f;
    it.light_path_of = bidir::LightPathAssignment(film.pixel_count(), std::max<uint64_t>(n, 1),
                                                  iteration, settings_.seed);
    probe_ = {};
    probe_.light_paths = double(n);
    if (it.plan.probe) plan_.begin_probe();
    // Before this iteration adds anything: the film adds estimates to its totals as they come.
    const std::vector<float> means_before =
        it.plan.probe ? pixel_means(film) : std::vector<float>();

    const auto light_start = std::chrono::steady_clock::now();
    size_chunks(n);
    trace_light_paths(scene, it, film);
    const double light_seconds = seconds_since(light_start);
    const bool any_merge = tech_.merge && n > 0 &&
                           (it.plan.merge_everywhere ||
                            std::find(it.plan.merge_mask->begin(), it.plan.merge_mask->end(), 1) !=
                                it.plan.merge_mask->end());
    if (any_merge) {
      const auto grid_start = std::chrono::steady_clock::now();
      grid_.build(vertices_, it.radius);
      grid_seconds_total_ +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - grid_start).count();
    }
    current_ = it;
    const auto camera_start = std::chrono::steady_clock::now();
    trace_camera_paths(scene, iteration, film);
    if (it.plan.probe) {
      probe_.light_vertices = double(vertices_.size());
      probe_.light_seconds = 0;
      probe_.light_seconds = light_chunk_seconds_;
      if (probe_.light_seconds == 0) probe_.light_seconds = light_seconds;
      if (probe_.camera_seconds == 0) probe_.camera_seconds = seconds_since(camera_start);
      plan_.finish_probe(probe_, means_before);
    }

    ++iterations_;
    last_radius_ = it.radius;
    vertices_total_ += vertices_.size();
    seconds_total_ +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  void finish(const Scene&, Film& film) override {
    if (techniques_.enabled())
      technique_files_ = techniques_.write(settings_.bidir.techniques_dir, film.iterations());
  }

  void report(nlohmann::json& stats) const override {
    if (tech_.adaptive) plan_.report(stats);
    nlohmann::json b;
    b["algorithm"] = name();
    b["mis"] = heuristic_ == MisHeuristic::Power ? "power" : "balance";
    b["light_paths_per_iteration"] = light_paths_;
    b["light_vertices_per_iteration"] = iterations_ ? double(vertices_total_) / iterations_ : 0.0;
    b["bytes_per_light_vertex"] = sizeof(LightVertex);
    b["light_vertex_buffer_bytes"] = vertices_.capacity() * sizeof(LightVertex);
    b["hash_grid_bytes"] = grid_.memory_bytes();
    if (tech_.merge)
      b["hash_grid_build_ms_per_iteration"] =
          iterations_ ? 1e3 * grid_seconds_total_ / iterations_ : 0.0;
    b["radius_initial"] = base_radius_;
    b["radius_last"] = last_radius_;
    b["radius_alpha"] = settings_.bidir.radius_alpha;
    b["ms_per_iteration"] = iterations_ ? 1e3 * seconds_total_ / iterations_ : 0.0;
    b["light_paths_ms_per_iteration"] =
        iterations_ ? 1e3 * light_seconds_total_ / iterations_ : 0.0;
    if (!technique_files_.empty()) b["technique_images"] = technique_files_;
    stats["bidir"] = b;
  }

 private:
  bool stores_vertices() const { return tech_.connect || tech_.merge; }

  // Scalar pixel means of the film's completed iterations (empty before the first); between
  // iterations only (film.h).
  static std::vector<float> pixel_means(const Film& film) {
    if (film.iterations() == 0) return {};
    const Image image = film.image();
    std::vector<float> means(image.pixels().size());
    for (size_t p = 0; p < means.size(); ++p) means[p] = scalar(image.pixels()[p]);
    return means;
  }

  // Chunks for n light paths (chunk_paths_for).
  void size_chunks(uint64_t n) {
    chunk_paths_ = chunk_paths_for(std::max<uint64_t>(n, 1));
    chunk_count_ = n ? (n + chunk_paths_ - 1) / chunk_paths_ : 0;
  }

  // ---- light subpaths -----------------------------------------------------------------------
  // Chunks are traced in parallel into a few reused buffers and appended, in chunk order, to
  // vertices_ and the splat image as they finish (a pipeline whose last stage is serial and in
  // order): no chunk is kept once appended, so the vertices are held once, not per chunk and
  // again concatenated, and the result is the concatenation in path order for any threads.
  void trace_light_paths(const Scene& scene, const Iteration& it, Film& film) {
    const auto start = std::chrono::steady_clock::now();
    vertices_.clear();
    path_begin_.resize(it.plan.light_paths + 1);
    light_chunk_seconds_ = 0;
    if (tech_.light_to_camera) {
      if (splat_image_.width() != film.width()) splat_image_ = Image(film.width(), film.height());
      std::fill(splat_image_.pixels().begin(), splat_image_.pixels().end(), Rgb(0.f));
    }
    const size_t tokens = std::min<size_t>(
        chunk_count_, 4 * size_t(std::max(1, tbb::this_task_arena::max_concurrency())));
    if (chunk_buffers_.size() < tokens) chunk_buffers_.resize(tokens);
    std::vector<LightChunk*> free_buffers;
    for (size_t i = 0; i < tokens; ++i) free_buffers.push_back(&chunk_buffers_[i]);
    std::mutex free_mutex;
    uint64_t next_chunk = 0, nonfinite = 0;
    if (tokens > 0)
      tbb::parallel_pipeline(
          tokens, tbb::make_filter<void, uint64_t>(tbb::filter_mode::serial_in_order,
                                                   [&](tbb::flow_control& fc) -> uint64_t {
                                                     if (next_chunk == chunk_count_) fc.stop();
                                                     return next_chunk++;
                                                   }) &
                      tbb::make_filter<uint64_t, LightChunk*>(
                          tbb::filter_mode::parallel,
                          [&](uint64_t c) {
                            LightChunk* chunk;
                            {
                              const std::lock_guard<std::mutex> lock(free_mutex);
                              chunk = free_buffers.back();
                              free_buffers.pop_back();
                            }
                            trace_chunk(scene, it, c, *chunk);
                            return chunk;
                          }) &
                      tbb::make_filter<LightChunk*, void>(
                          tbb::filter_mode::serial_in_order, [&](LightChunk* chunk) {
                            append_chunk(it, *chunk);
                            nonfinite += chunk->nonfinite;
                            const std::lock_guard<std::mutex> lock(free_mutex);
                            free_buffers.push_back(chunk);
                          }));
    path_begin_[it.plan.light_paths] = uint32_t(vertices_.size());
    if (tech_.light_to_camera) {
      if (nonfinite) film.count_nonfinite(nonfinite);
      film.add_image(splat_image_);
    }
    light_seconds_total_ += seconds_since(start);
  }

  // Light paths of chunk c, traced into chunk (its storage reused).
  void trace_chunk(const Scene& scene, const Iteration& it, uint64_t c, LightChunk& chunk) const {
    thread_local ScratchArena arena;
    chunk.vertices.clear();
    chunk.path_ends.clear();
    chunk.splats.clear();
    chunk.splat_terms.clear();
    chunk.nonfinite = 0;
    const auto chunk_start = std::chrono::steady_clock::now();
    chunk.first_path = c * chunk_paths_;
    const uint64_t last = std::min<uint64_t>(chunk.first_path + chunk_paths_, it.plan.light_paths);
    for (uint64_t path = chunk.first_path; path < last; ++path) {
      arena.reset();
      trace_light_path(scene, it, path, chunk, arena);
      chunk.path_ends.push_back(uint32_t(chunk.vertices.size()));
    }
    chunk.seconds =
        it.plan.probe && settings_.bidir.measured_costs ? seconds_since(chunk_start) : 0;
  }

  // The next chunk in path order: vertex i of path p lands at path_begin_[p] + i; its splats
  // are added in the order they were made (deterministic sums).
  void append_chunk(const Iteration& it, const LightChunk& chunk) {
    const size_t need = vertices_.size() + chunk.vertices.size();
    if (need > vertices_.capacity()) {
      // Grow to what the chunks so far predict for the whole iteration, plus a tenth, rather
      // than by doubling: this is the largest buffer, kept from one iteration to the next.
      const uint64_t chunks_done = chunk.first_path / chunk_paths_ + 1;
      const size_t predicted = size_t(double(need) * double(chunk_count_) / double(chunks_done));
      vertices_.reserve(std::max(need, predicted + predicted / 10));
    }
    const uint32_t base = uint32_t(vertices_.size());
    vertices_.insert(vertices_.end(), chunk.vertices.begin(), chunk.vertices.end());
    for (size_t i = 0; i < chunk.path_ends.size(); ++i)
      path_begin_[chunk.first_path + i] = base + (i ? chunk.path_ends[i - 1] : 0);
    light_chunk_seconds_ += chunk.seconds;
    for (size_t i = 0; i < chunk.splats.size(); ++i) {
      const Splat& s = chunk.splats[i];
      splat_image_[s.pixel] += s.value;
      if (techniques_.enabled()) techniques_.add(s.technique, s.pixel, s.value);
      if (it.plan.probe)
        plan_.add_light_trace(s.pixel, scalar(s.value), &chunk.splat_terms[i], it.rules.counts(),
                              it.radius);
    }
  }

  void trace_light_path(const Scene& scene, const Iteration& it, uint64_t path, LightChunk& chunk,
                        ScratchArena& arena) const {
    const LightSampler& sampler = scene.light_sampler();
    if (sampler.empty()) return;
    Pcg32 rng = Pcg32::for_sample(path, it.index, hash_combine(settings_.seed, 0x11947ull));
    float pmf;
    const Light* light = sampler.sample(rng.next_float(), &pmf);
    const Vec2 u_pos = rng.next_2d(), u_dir = rng.next_2d();
    if (!light || !(pmf > 0)) return;
    const auto le = light->sample_le(u_pos, u_dir);
    if (!le || !(le->pdf_pos > 0) || !(le->pdf_dir > 0) || le->radiance.is_black()) return;
    const float emission_pdf = pmf * le->pdf_pos * le->pdf_dir;
    Rgb beta = le->radiance * (le->cos_at_light / emission_pdf);
    const float beta_start = beta.max_component();
    const int max_depth = settings_.max_depth;

    Ray ray = ray_leaving_light(*le, *light);
    MisSums mis;
    float segment = 0;  // distance since the previous real vertex (interfaces are skipped)
    int depth = 0;
    for (;;) {
      SurfaceInteraction si;
      if (!scene.intersect(ray, &si)) break;
      segment += si.t;
      Bsdf bsdf;
      if (si.material) bsdf = si.material->bsdf(si, arena);
      if (!bsdf.valid()) {
        ray = si.spawn_ray(ray.d);
        continue;
      }
      ++depth;
      if (depth == 1) {
        mis = light_subpath_start(it.rules, *light, pmf, *le, si, segment);
      } else {
        it.rules.hit(mis, segment * segment, bidir::geometric_cos(si, si.wo));
      }
      segment = 0;
      if (depth > max_depth) break;

      if (!bsdf.is_delta()) {
        if (stores_vertices()) {
          chunk.vertices.push_back(
              bidir::pack_light_vertex({si.p, si.wo, scene.primitive_index(si), depth, beta, mis}));
        }
        if (tech_.light_to_camera)
          connect_to_camera(scene, it, si, bsdf, beta, mis, depth, rng, chunk);
      }
      if (depth + 1 > max_depth) break;

      const float uc = rng.next_float();
      const auto bs = bsdf.sample(si.wo, uc, rng.next_2d(), TransportMode::Importance);
      if (!bs) break;
      const float pdf_fwd =
          bs->pdf_is_proportional ? bsdf.pdf(si.wo, bs->wi, TransportMode::Importance) : bs->pdf;
      bidir::scatter_update(it.rules, mis, si, bsdf, si.wo, bs->wi, TransportMode::Importance,
                            bs->is_specular(), pdf_fwd);
      beta *= bs->f * (bsdf.abs_cos(bs->wi) / bs->pdf);
      if (beta.is_black()) break;
      ray = si.spawn_ray(bs->wi);
      // Russian roulette on the throughput relative to the emitted one (importance carries no
      // radiance scaling at refractions, so no eta correction).
      const float rr = beta.max_component() / beta_start;
      if (rr < 1 && depth > 1) {
        const float q = std::max(0.f, 1 - rr);
        if (rng.next_float() < q) break;
        beta = beta / (1 - q);
      }
    }
  }

  // t = 1: the light vertex seen through a lens point; splat recorded in the chunk.
  void connect_to_camera(const Scene& scene, const Iteration& it, const SurfaceInteraction& si,
                         const Bsdf& bsdf, Rgb beta, const MisSums& mis, int depth, Pcg32& rng,
                         LightChunk& chunk) const {
    const Camera& camera = scene.camera();
    const auto cs = camera.sample_wi(si.p, rng.next_2d());
    if (!cs || !(cs->importance > 0)) return;
    const Rgb f = bsdf.f(si.wo, cs->wi, TransportMode::Importance) * bsdf.abs_cos(cs->wi);
    if (f.is_black()) return;
    // Pixel importance is pixel_count * We * f(r - c_p) / integral f; each pixel is estimated by
    // N light paths. Every pixel whose filter support holds the raster point r gets a splat,
    // MIS-weighted against its own camera technique (raster density pdf(r - c_p)).
    const float scale =
        cs->importance * float(camera.pixel_count()) / (cs->pdf_w * float(it.plan.light_paths));
    const size_t first_splat = chunk.splats.size();
    filter_.for_each_pixel(
        cs->raster, camera.width(), camera.height(), [&](int x, int y, const FilterSample& fs) {
          const uint32_t pixel = uint32_t(y * camera.width() + x);
          const MisRules& rules = it.plan.merges(pixel) ? it.rules : it.rules_no_merge;
          const bidir::TechniqueTerms terms =
              bidir::terms_light_to_camera(rules, camera, si, bsdf, si.wo, mis, cs->p_lens, fs.pdf);
          const float w = tech_.unweighted ? 1.f : terms.weight(rules.counts());
          const Rgb value = beta * f * (scale * w) * (fs.weight * fs.pdf);
          if (value.is_black()) return;
          if (!value.is_finite()) {
            ++chunk.nonfinite;
            return;
          }
          chunk.splats.push_back({pixel, TechniqueImages::key(false, depth + 1, 1), value});
          if (it.plan.probe) chunk.splat_terms.push_back(terms);
        });
    if (chunk.splats.size() > first_splat && scene.occluded(si.spawn_ray_to(cs->p_lens))) {
      chunk.splats.resize(first_splat);
      if (it.plan.probe) chunk.splat_terms.resize(first_splat);
    }
  }

  // ---- camera subpaths ----------------------------------------------------------------------
  // The seam's per-pixel call: the camera subpath of this iteration (current_).
  Rgb estimate(const Scene& scene, const CameraSample& sample, Pcg32& rng, ScratchArena& arena,
               uint64_t* nonfinite) const override {
    PixelAccumulator acc;
    acc.pixel = sample.pixel;
    acc.filter_weight = sample.filter_weight;
    if (techniques_.enabled()) acc.techniques = &techniques_;
    const Iteration& it = current_;
    acc.rules = it.plan.merges(sample.pixel) ? &it.rules : &it.rules_no_merge;
    if (it.plan.probe) {
      acc.plan = &plan_;
      acc.radius = it.radius;
      acc.candidate_sums = plan_.pixel_start(sample.pixel);
    }
    const auto start = std::chrono::steady_clock::now();
    camera_path(scene, it, sample, rng, acc, arena);
    *nonfinite += acc.nonfinite;
    if (it.plan.probe) {
      plan_.pixel_end(sample.pixel, acc.candidate_sums);
      if (settings_.bidir.measured_costs) acc.work.camera_seconds = seconds_since(start);
      add_probe_work(acc.work);
    }
    return acc.sum;
  }

  void add_probe_work(const bidir::ProbeWork& w) const {
    std::lock_guard<std::mutex> lock(probe_mutex_);
    probe_.camera_vertices += w.camera_vertices;
    probe_.nondelta_camera_vertices += w.nondelta_camera_vertices;
    probe_.connections += w.connections;
    probe_.merge_queries += w.merge_queries;
    probe_.photons += w.photons;
    probe_.camera_seconds += w.camera_seconds;
    probe_.connect_seconds += w.connect_seconds;
    probe_.merge_seconds += w.merge_seconds;
  }

  void camera_path(const Scene& scene, const Iteration& it, const CameraSample& sample, Pcg32& rng,
                   PixelAccumulator& acc, ScratchArena& arena) const {
    const Camera& camera = scene.camera();
    const LightSampler& lights = scene.light_sampler();
    const uint64_t pixel = sample.pixel;
    Ray ray = sample.ray;
    const float pdf_camera = bidir::camera_pdf_w(camera, ray.o, ray.d, sample.filter_pdf);
    if (!(pdf_camera > 0)) return;
    const MisRules& rules = *acc.rules;
    const bool merges = tech_.merge && it.plan.merges(pixel);
    const bool timed = acc.plan && settings_.bidir.measured_costs;
    MisSums mis = rules.camera_start(pdf_camera);
    const int max_depth = settings_.max_depth;
    const uint64_t light_path = it.light_path_of.light_path(pixel);

    Rgb beta(1.f);
    Vec3 prev_p = ray.o;
    int depth = 0;              // surface vertices so far
    bool specular_path = true;  // every bounce so far was specular
    float segment = 0;
    float eta_scale = 1;
    // Emitters: MIS-weighted when connections take part, else only via delta-only chains.
    bidir::TechniqueTerms terms;
    bool weighted = false;  // the last emitter weight came from terms
    auto emitter_weight = [&](const Light& light, const SurfaceInteraction* hit, const MisSums& m) {
      weighted = false;
      if (depth == 0) return 1.f;
      if (!tech_.connect) return specular_path ? 1.f : 0.f;
      weighted = true;
      terms = bidir::terms_emitter_hit(rules, light, lights.pmf(&light), prev_p, ray.d, hit, m);
      return terms.weight(rules.counts());
    };

    for (;;) {
      SurfaceInteraction si;
      if (!scene.intersect(ray, &si)) {
        for_each_emitter_seen(scene.infinite_lights(), ray, nullptr, [&](const Light& l, Rgb Le) {
          const float w = emitter_weight(l, nullptr, mis);
          if (w > 0) acc.add(false, 0, depth + 2, beta * Le * w, weighted ? &terms : nullptr);
        });
        break;
      }
      segment += si.t;
      Bsdf bsdf;
      if (si.material) bsdf = si.material->bsdf(si, arena);
      MisSums at_hit = mis;
      rules.hit(at_hit, segment * segment, bidir::geometric_cos(si, si.wo));

      for_each_emitter_seen(scene.infinite_lights(), ray, &si, [&](const Light& l, Rgb Le) {
        const float w = emitter_weight(l, &si, at_hit);
        if (w > 0) acc.add(false, 0, depth + 2, beta * Le * w, weighted ? &terms : nullptr);
      });
      if (!bsdf.valid()) {
        ray = si.spawn_ray(ray.d);
        continue;
      }
      ++depth;
      mis = at_hit;
      segment = 0;
      if (depth > max_depth) break;

      const bool delta = bsdf.is_delta();
      ++acc.work.camera_vertices;
      if (!delta) {
        ++acc.work.nondelta_camera_vertices;
        if (tech_.connect) {
          next_event(scene, rules, si, bsdf, beta, mis, depth, rng, acc);
          const auto t0 = timed ? std::chrono::steady_clock::now() : Clock::time_point{};
          connect_to_light_paths(scene, it, rules, si, bsdf, beta, mis, depth, light_path, rng,
                                 arena, acc);
          if (timed) acc.work.connect_seconds += seconds_since(t0);
        }
        if (merges) {
          const auto t0 = timed ? std::chrono::steady_clock::now() : Clock::time_point{};
          merge(scene, it, rules, si, bsdf, beta, mis, depth, acc);
          if (timed) acc.work.merge_seconds += seconds_since(t0);
        }
      }

      const float uc = rng.next_float();
      const auto bs = bsdf.sample(si.wo, uc, rng.next_2d(), TransportMode::Radiance);
      if (!bs) break;
      // PPM / lt: the non-delta part of this vertex was estimated by merging (or belongs to light
      // tracing); only its delta lobes carry the camera path on.
      if (tech_.camera_stops && !delta && !bs->is_specular()) break;
      const float pdf_fwd =
          bs->pdf_is_proportional ? bsdf.pdf(si.wo, bs->wi, TransportMode::Radiance) : bs->pdf;
      bidir::scatter_update(rules, mis, si, bsdf, si.wo, bs->wi, TransportMode::Radiance,
                            bs->is_specular(), pdf_fwd);
      beta *= bs->f * (bsdf.abs_cos(bs->wi) / bs->pdf);
      specular_path = specular_path && bs->is_specular();
      if (bs->is_transmission()) eta_scale *= sqr(bs->eta);
      if (beta.is_black()) break;
      prev_p = si.p;
      ray = si.spawn_ray(bs->wi);
      if (!survives_russian_roulette(beta, eta_scale, depth, rng)) break;
    }
  }

  void next_event(const Scene& scene, const MisRules& rules, const SurfaceInteraction& si,
                  const Bsdf& bsdf, Rgb beta, const MisSums& mis, int depth, Pcg32& rng,
                  PixelAccumulator& acc) const {
    const float u_light = rng.next_float();
    const Vec2 u = rng.next_2d();
    const auto d = sample_direct_light(scene, si, bsdf, u_light, u);
    if (!d) return;
    const bidir::TechniqueTerms terms =
        bidir::terms_next_event(rules, *d->light, d->pmf, d->ls, si, bsdf, mis);
    const float w = terms.weight(rules.counts());
    const Rgb value = beta * d->f * d->ls.radiance * (w / (d->pmf * d->ls.pdf_w));
    if (value.is_black()) return;
    if (scene.occluded(d->shadow)) return;
    acc.add(false, 1, depth + 1, value, &terms);
  }

  // Connections to the vertices of `connections` light paths: the pixel's own, then paths drawn
  // uniformly (each light path is an independent sample, so any choice is unbiased); each
  // connection is one of c samples, hence the 1 / c.
  void connect_to_light_paths(const Scene& scene, const Iteration& it, const MisRules& rules,
                              const SurfaceInteraction& si, const Bsdf& bsdf, Rgb beta,
                              const MisSums& mis, int depth, uint64_t light_path, Pcg32& rng,
                              ScratchArena& arena, PixelAccumulator& acc) const {
    const uint64_t n = it.plan.light_paths;
    const int c = it.plan.connections;
    if (n == 0 || c == 0) return;
    const Rgb scaled = beta / float(c);
    for (int j = 0; j < c; ++j) {
      const uint64_t path =
          j == 0 ? light_path : std::min<uint64_t>(uint64_t(rng.next_float() * double(n)), n - 1);
      connect_to_light_path(scene, rules, si, bsdf, scaled, mis, depth, path, arena, acc);
    }
  }

  void connect_to_light_path(const Scene& scene, const MisRules& rules,
                             const SurfaceInteraction& si, const Bsdf& bsdf, Rgb beta,
                             const MisSums& mis, int depth, uint64_t light_path,
                             ScratchArena& arena, PixelAccumulator& acc) const {
    for (uint32_t i = path_begin_[light_path]; i < path_begin_[light_path + 1]; ++i) {
      const LightVertex& stored = vertices_[i];
      // Stored in increasing depth: once too long, all the rest are too.
      if (bidir::light_vertex_depth(stored) + depth > settings_.max_depth) break;
      const LightVertexData v = bidir::unpack_light_vertex(stored);
      const SurfaceInteraction light_si = scene.interaction_at(v.primitive, v.p, v.wo);
      const Bsdf light_bsdf = light_si.material->bsdf(light_si, arena);
      if (!light_bsdf.valid()) continue;
      const Vec3 d = light_si.p - si.p;
      const float dist2 = length_squared(d);
      if (!(dist2 > 0)) continue;
      const Vec3 dir = d / std::sqrt(dist2);
      const Rgb f_camera = bsdf.f(si.wo, dir, TransportMode::Radiance) * bsdf.abs_cos(dir);
      if (f_camera.is_black()) continue;
      const Rgb f_light =
          light_bsdf.f(v.wo, -dir, TransportMode::Importance) * light_bsdf.abs_cos(dir);
      if (f_light.is_black()) continue;
      ++acc.work.connections;
      const bidir::TechniqueTerms terms =
          bidir::terms_connection(rules, light_si, light_bsdf, v.wo, v.mis, si, bsdf, mis);
      const float w = terms.weight(rules.counts());
      const Rgb value = beta * v.throughput * f_camera * f_light * (w / dist2);
      if (value.is_black()) continue;
      if (scene.occluded(spawn_ray_between(si, light_si))) continue;
      acc.add(false, v.depth + 1, depth + 1, value, &terms);
    }
  }

  // Merging accepts a photon only if light could have reached the query's surface through it
  // (no leaks through zero-thickness walls):
  //  - it lies within half the radius of the query's tangent plane (a photon on another sheet
  //    of the same mesh, or behind a corner, is not density on this surface);
  //  - it arrived on a side the query's BSDF scatters from (f = 0 otherwise);
  //  - a photon on another shape (mesh or sphere) than the query must see the query: one shadow
  //    ray from the query to a point just off the photon on the side it arrived from. Photons
  //    on the query's own shape are trusted, so the ray is traced only near shape boundaries.
  // Each test only removes photons; at distance 0 (the partition test's merges) all pass.
  void merge(const Scene& scene, const Iteration& it, const MisRules& rules,
             const SurfaceInteraction& si, const Bsdf& bsdf, Rgb beta, const MisSums& mis,
             int depth, PixelAccumulator& acc) const {
    ++acc.work.merge_queries;
    const int max_depth = settings_.max_depth;
    const Scene::PrimitiveRange own_shape = scene.shape_primitives(si);
    const float max_off_plane = 0.5f * it.radius;
    grid_.for_each_near(si.p, vertices_, [&](uint32_t index, Vec3 q) {
      ++acc.work.photons;
      const LightVertex& stored = vertices_[index];
      const int light_depth = bidir::light_vertex_depth(stored);
      if (light_depth + depth - 1 > max_depth) return;
      if (std::abs(dot(q - si.p, si.ng)) > max_off_plane) return;
      const LightVertexData v = bidir::unpack_light_vertex(stored);
      // The photon's throughput carries the flux through the surface (geometric cosine); the
      // camera vertex integrates with the shading cosine: |ns . wi| / |ng . wi|, as NEE and
      // connections have it through abs_cos (Veach 1997, section 5.3).
      const float cos_geometric = bidir::geometric_cos(si, v.wo);
      if (!(cos_geometric > 0)) return;
      const Rgb f =
          bsdf.f(si.wo, v.wo, TransportMode::Radiance) * (bsdf.abs_cos(v.wo) / cos_geometric);
      if (f.is_black()) return;
      if (!own_shape.contains(v.primitive) &&
          !photon_visible(scene, si, v.primitive, q, v.wo, it.radius))
        return;
      const bidir::TechniqueTerms terms = bidir::terms_merge(rules, v.wo, v.mis, si, bsdf, mis);
      const float w = tech_.unweighted ? 1.f : terms.weight(rules.counts());
      acc.add(true, light_depth + 1, depth + 1,
              beta * f * v.throughput * (w * it.merge_normalization), &terms);
    });
  }

  // Whether light arriving along wo at the query could be the photon's (a photon on another
  // shape than the query). Each point must lie on the lit side (the side of wo) of the other's
  // surface, within a ten-thousandth of the radius: a photon on the far face of a
  // zero-thickness wall, or a query behind the photon's wall, fails here. Then a shadow ray
  // between the two, each end offset off its own surface to the side of wo, catches a wall
  // between them (a floor continuing under the wall into the next room). The photon's hit
  // record is rebuilt for its normal and error bounds.
  bool photon_visible(const Scene& scene, const SurfaceInteraction& si, uint32_t primitive, Vec3 q,
                      Vec3 wo, float radius) const {
    const SurfaceInteraction photon = scene.interaction_at(primitive, q, wo);
    const float tolerance = 1e-4f * radius;
    const Vec3 n_query = face_forward(si.ng, wo), n_photon = face_forward(photon.ng, wo);
    if (dot(q - si.p, n_query) < -tolerance || dot(si.p - q, n_photon) < -tolerance) return false;
    const Vec3 origin = si.offset_origin(wo);
    const Vec3 target = photon.offset_origin(wo);
    return !scene.occluded({origin, target - origin, 1.f - 1e-6f});
  }

  BidirAlgorithm algorithm_;
  Techniques tech_;
  IntegratorSettings settings_;
  MisHeuristic heuristic_;
  PixelFilter filter_;  // the scene camera's, set by prepare(): light-tracing splats
  Iteration current_;   // this iteration's constants, for estimate()
  float base_radius_ = 0, last_radius_ = 0;
  uint64_t light_paths_ = 0;

  // Per-iteration buffers, reused.
  uint64_t chunk_paths_ = kMaxChunkPaths;  // light paths per chunk (chunk_paths_for)
  uint64_t chunk_count_ = 0;
  std::vector<LightChunk> chunk_buffers_;  // one per chunk in flight (trace_light_paths)
  double light_chunk_seconds_ = 0;         // probe iterations: the chunks' tracing times, summed
  std::vector<LightVertex> vertices_;
  std::vector<uint32_t> path_begin_;
  HashGrid grid_;
  Image splat_image_;
  // Written by the camera pass (estimate() is const): each pixel by the one task that owns it.
  mutable TechniqueImages techniques_;

  // Statistics.
  uint32_t iterations_ = 0;
  uint64_t vertices_total_ = 0;
  double seconds_total_ = 0;
  double grid_seconds_total_ = 0;   // of seconds_total_, building the hash grid
  double light_seconds_total_ = 0;  // of seconds_total_, tracing light paths (with their splats)
  std::vector<std::string> technique_files_;

  // adaptive-vcm: the plan, and the work of the current probe iteration.
  mutable bidir::AdaptivePlan plan_;
  mutable bidir::ProbeWork probe_;
  mutable std::mutex probe_mutex_;
};

}  // namespace

std::unique_ptr<Integrator> make_bidir_integrator(BidirAlgorithm algorithm,
                                                  const IntegratorSettings& settings) {
  return std::make_unique<BidirIntegrator>(algorithm, settings);
}

}  // namespace caustica
