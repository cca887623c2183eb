// The bidirectional core's class, shared by its three source files (not an interface:
// integrators outside bidir/ use bidir_integrator.h): bidir_integrator.cpp (iterations,
// configuration, statistics), bidir_light_paths.cpp (light subpaths, their storage and the
// light-tracing splats) and bidir_camera_paths.cpp (camera subpaths: NEE, connections, merging).
#pragma once

#include <tbb/enumerable_thread_specific.h>

#include <chrono>
#include <nlohmann/json.hpp>
#include <type_traits>
#include <vector>

#include "core/arena.h"
#include "core/rng.h"
#include "film/pixel_filter.h"
#include "image/image.h"
#include "integrators/bidir/adaptive_plan.h"
#include "integrators/bidir/bidir_guiding.h"
#include "integrators/bidir/bidir_integrator.h"
#include "integrators/bidir/hash_grid.h"
#include "integrators/bidir/light_path_assignment.h"
#include "integrators/bidir/light_vertex.h"
#include "integrators/bidir/probe_film.h"
#include "integrators/bidir/segment_moments.h"
#include "integrators/bidir/technique_images.h"
#include "integrators/bidir/techniques.h"
#include "integrators/camera_path.h"
#include "integrators/path_tracer.h"

namespace caustica::bidir {
using Clock = std::chrono::steady_clock;

// Light paths per chunk: at most 1024, fewer when that would leave fewer than 64 chunks (a small
// image has few light paths; 4 chunks of 1024 kept 2 threads half idle at 64x64). It depends on
// the path count only, never on the threads, and the vertices and splats are concatenated in
// path order whatever the chunk size: the images do not depend on it.
constexpr uint64_t kMaxChunkPaths = 1024, kMinChunkPaths = 64, kMinChunks = 64;
inline uint64_t chunk_paths_for(uint64_t light_paths) {
  return std::clamp((light_paths + kMinChunks - 1) / kMinChunks, kMinChunkPaths, kMaxChunkPaths);
}
constexpr float kDefaultRadiusFactor = 0.003f;

// Which techniques take part (tech. rep. section 6, SmallVCM's switches).
struct Techniques {
  bool light_to_camera = false;  // t = 1 splats
  bool light_origin = false;     // ... including area lights' emission points (s = 1, t = 1)
  bool connect = false;          // NEE, emitter hits and connections, MIS-weighted
  bool merge = false;            // vertex merging
  bool camera_stops = false;     // camera subpaths end at their first non-delta vertex
  bool unweighted = false;       // single-technique estimators (lt, ppm): all weights 1
  bool adaptive = false;         // configuration chosen per iteration (adaptive_plan.h)
  bool guided = false;           // subpaths guided by learned fields (bidir_guiding.h)
};

struct Splat {
  uint32_t pixel;
  uint32_t technique;
  Rgb value;
};

// Scalar of a contribution for the adaptive plan's moments.
inline float scalar(Rgb v) { return (v.r + v.g + v.b) * (1.f / 3.f); }

// A stored light vertex's CorrelationTrack (correlation-aware MIS), one cache line per vertex
// at the vertex's index: up to kInline entries in the line itself, more in a pool (first). A
// merge reads it for every photon it accepts, in random order: one miss, prefetched when the
// range search finds the photon (a pool of all entries took a second, dependent miss that
// was most of the correlation's cost).
struct alignas(64) StoredTrack {
  static constexpr uint32_t kInline = 3;
  float own_total = 1, seg_cos = 0, seg_dist2 = 1;
  uint32_t count = 0;
  uint32_t first = 0;  // in the pool, when count > kInline
  CorrelationEntry inline_entries[kInline];
};
static_assert(sizeof(StoredTrack) == 64, "a stored track is meant to fill one cache line");

// What one chunk of light paths leaves behind.
struct LightChunk {
  uint64_t first_path = 0;
  std::vector<LightVertex> vertices;
  // Correlation-aware MIS: per vertex its track, the entries in one pool (first: in the pool).
  std::vector<StoredTrack> tracks;
  std::vector<CorrelationEntry> track_entries;
  std::vector<uint32_t> path_ends;  // per path: vertices.size() after it
  std::vector<Splat> splats;
  // Probes: the MIS terms of the splats that land in recorded pixels, in splat order.
  std::vector<TechniqueTerms> splat_terms;
  uint64_t nonfinite = 0;
  uint64_t rays = 0;   // rays traced (every bounce, delta ones too)
  double seconds = 0;  // probe iterations: time spent tracing the chunk
};

// Per-iteration constants.
struct Iteration {
  uint32_t index = 0;
  IterationPlan plan;  // light paths, connections, merging
  float radius = 0;
  MisRules rules{MisHeuristic::Balance, false, false, 1, 0};
  MisRules rules_no_merge = rules;  // in pixels that do not merge (adaptive-vcm)
  // In pixels that path trace (adaptive-vcm, PixelMode::PathTrace) when pt's estimator is not
  // at hand (technique images): emitter hits and next event estimation only.
  MisRules rules_camera_only = rules;
  // In the pixels a probe records (plan.records): its connections and merging.
  MisRules rules_probe = rules;
  float merge_normalization = 0;      // 1 / (N pi r^2)
  LightPathAssignment light_path_of;  // pixel -> the light subpath it connects to
  // The rules every technique of a pixel that runs the core weights by (its camera subpaths
  // and the light-tracing splats landing in it): a probe's if the probe records the pixel,
  // else the choice's with or without merging. One function for both, so that they agree.
  const MisRules& rules_at(size_t pixel) const {
    if (plan.records(pixel)) return rules_probe;
    return plan.merges(pixel) ? rules : rules_no_merge;
  }
};

// A light vertex rebuilt for connections: its interaction and BSDF (from the stored vertex) and
// its guides. The vertices of the pixel's own light path are rebuilt once and kept for every
// camera vertex of the pixel (PixelAccumulator::own_path), not once per camera vertex.
struct RebuiltLightVertex {
  SurfaceInteraction si;
  Bsdf bsdf;
  VertexGuides guides;
  VertexProbabilities probabilities;  // of its connections (technique_probabilities.h)
  bool built = false;
};
static_assert(std::is_trivially_destructible_v<RebuiltLightVertex>,
              "arena memory is not destroyed");

// A value added to the pixel and, if technique images are kept, to its technique.
struct PixelAccumulator {
  Rgb sum;
  // The pixel's own light path rebuilt so far (arena memory, one entry per stored vertex).
  RebuiltLightVertex* own_path = nullptr;
  TechniqueImages* techniques = nullptr;
  size_t pixel = 0;
  uint64_t nonfinite = 0;
  float filter_weight = 1;  // the camera sample's pixel-filter weight (pixel_filter.h)
  // adaptive-vcm's photon-mapping pixels (PixelMode::Stop): ppm's estimator, every weight 1.
  bool stops = false;
  // Probe iterations of adaptive-vcm: each contribution with its MIS terms, and the work.
  AdaptivePlan* plan = nullptr;
  AdaptivePlan::CandidateSums candidate_sums;
  const MisRules* rules = nullptr;
  ProbeWork work;
  // sum is the estimate before the filter weight (the seam applies it); technique images get
  // each value already weighted, so that they add up to the image. terms: the value's MIS
  // terms (nullptr: a path only one technique makes); share: for a connection, whether it went
  // to the pixel's own light path (AdaptivePlan::add).
  void add(bool merge, int s, int t, Rgb value, const TechniqueTerms* terms = nullptr,
           AdaptivePlan::Share share = AdaptivePlan::Share::None) {
    if (!value.is_finite()) {
      ++nonfinite;
      return;
    }
    sum += value;
    if (techniques)
      techniques->add(TechniqueImages::key(merge, s, t), pixel, value * filter_weight);
    if (plan)
      plan->add(candidate_sums, scalar(value * filter_weight), terms, rules->counts(), share);
  }
};

inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Techniques techniques_of(BidirAlgorithm a);
const char* name_of(BidirAlgorithm a);

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

  void prepare(const Scene& scene, Film& film) override;

  void render_iteration(const Scene& scene, uint32_t iteration, Film& film) override;

  void finish(const Scene&, Film& film) override;

  void report(nlohmann::json& stats) const override;

  // guided-bpt / guided-vcm: the passes weighted by the inverse of their variance
  // (--guiding-combine, as guided-pt; image/inverse_variance.h); adaptive-vcm: its probes
  // weighted against the other iterations (probe_film.h); else the film's plain average.
  Image image(const Film& film) const override;
  // Under MPI: guided-bpt / guided-vcm's current pass, adaptive-vcm's probes, as exact sums
  // over the ranks (a pass that teaches and every probe are rendered whole by every rank: rank
  // 0's are the total).
  std::span<FixedSum> sums_over_ranks(bool root) override;

  // guided-bpt / guided-vcm: the learned fields (tests).
  const BidirGuiding& guiding() const { return guiding_; }

  // adaptive-vcm's probes are shared: every MPI rank renders them, and the means that normalise
  // their variances come from the film of all ranks (observe_film), so every rank makes the
  // choice one process makes. So are the training and trial passes of guided-bpt/guided-vcm:
  // every rank learns the same fields and takes the same decisions (at a fixed --spp).
  bool shared_iteration(uint32_t iteration) const override {
    return (tech_.adaptive && plan_.is_probe(iteration)) || (tech_.guided && guiding_.teaches());
  }
  bool observes_film() const override { return tech_.adaptive; }
  void observe_film(const Film& before) override {
    observed_means_ = pixel_means(before);
    observed_ = true;
  }
  // adaptive-vcm: the pixel moments of the iterations since the last probe (segment_moments.h).
  std::span<FixedSum> learning_sums() override {
    return tech_.adaptive ? segment_.sums() : std::span<FixedSum>();
  }
  void observe_learning_sums(std::span<const FixedSum> total) override {
    observed_segment_.assign(total.begin(), total.end());
  }

 private:
  bool stores_vertices() const { return tech_.connect || tech_.merge; }
  // --merge-mis correlation-aware, which only vcm takes.
  // (The command line refuses a --max-depth beyond what a CorrelationTrack holds; other callers
  // get the balance heuristic there.)
  bool correlation_aware() const {
    return settings_.bidir.correlation_aware && algorithm_ == BidirAlgorithm::Vcm &&
           settings_.max_depth <= CorrelationTrack::kMaxEntries;
  }
  // A light vertex's track as stored (its entries beyond StoredTrack::kInline appended to the
  // pool), and the track stored with light vertex `index` (correlation-aware MIS).
  static StoredTrack store_track(const CorrelationTrack& track,
                                 std::vector<CorrelationEntry>& pool);
  void load_track(uint32_t index, CorrelationTrack* out) const;

  // Scalar pixel means of the film's completed iterations (empty before the first); between
  // iterations only (film.h).
  static std::vector<float> pixel_means(const Film& film);

  // Chunks for n light paths (chunk_paths_for).
  void size_chunks(uint64_t n);

  // ---- light subpaths -----------------------------------------------------------------------
  // Chunks are traced in parallel into a few reused buffers and appended, in chunk order, to
  // vertices_ and the splat image as they finish (a pipeline whose last stage is serial and in
  // order): no chunk is kept once appended, so the vertices are held once, not per chunk and
  // again concatenated, and the result is the concatenation in path order for any threads.
  void trace_light_paths(const Scene& scene, const Iteration& it, Film& film);

  // Light paths of chunk c, traced into chunk (its storage reused).
  void trace_chunk(const Scene& scene, const Iteration& it, uint64_t c, LightChunk& chunk) const;

  // The next chunk in path order: vertex i of path p lands at path_begin_[p] + i; its splats
  // are added in the order they were made (deterministic sums).
  void append_chunk(const Iteration& it, const LightChunk& chunk);

  void trace_light_path(const Scene& scene, const Iteration& it, uint64_t path, LightChunk& chunk,
                        ScratchArena& arena) const;

  // s = 1, t = 1: an area light's emission point seen through a lens point (the light seen
  // directly, the other way than a camera ray hitting it); splats recorded in the chunk.
  void connect_emission_to_camera(const Scene& scene, const Iteration& it, const Light& light,
                                  float pmf, const LightLeSample& le, uint64_t path,
                                  LightChunk& chunk) const;
  // Splats a lens connection landing at `raster` to every pixel whose filter support holds it:
  // value_of(w) is the estimate with MIS weight w, terms_of(rules, raster_density) the pixel's
  // MIS terms. Returns whether any splat was recorded. The caller has traced the shadow ray
  // first: a blocked connection costs no densities or terms.
  template <typename ValueOf, typename TermsOf>
  bool splat_lens_connection(const Camera& camera, const Iteration& it, Vec2 raster,
                             uint32_t technique, const ValueOf& value_of, const TermsOf& terms_of,
                             LightChunk& chunk) const;
  // Whether a lens connection landing at `raster` can splat anywhere: false when every pixel
  // whose support may hold it path traces or maps photons alone (adaptive-vcm's PixelMode;
  // those take no splat, splat_lens_connection), so that the caller skips the BSDF, the shadow
  // ray and the densities of a connection nobody takes. True for every other integrator.
  bool splat_can_land(const Camera& camera, const Iteration& it, Vec2 raster) const;
  // t = 1: the light vertex seen through a lens point; splat recorded in the chunk. Returns
  // the connection's unweighted estimate (0 when blocked), what the guiding of light subpaths
  // learns from.
  // probabilities: the vertex's (technique_probabilities.h), the lens connection's among them.
  Rgb connect_to_camera(const Scene& scene, const Iteration& it, const SurfaceInteraction& si,
                        const Bsdf& bsdf, const VertexGuides& guides,
                        const VertexProbabilities& probabilities, Rgb beta, const MisSums& mis,
                        int depth, Pcg32& rng, LightChunk& chunk) const;

  // ---- camera subpaths ----------------------------------------------------------------------
  // The seam's per-pixel call: the camera subpath of this iteration (current_).
  Rgb estimate(const Scene& scene, const CameraSample& sample, Pcg32& rng, ScratchArena& arena,
               uint64_t* nonfinite) const override;

  // A pixel's work, into its thread's (pixel_work_: no lock per pixel; recorded: a pixel the
  // probe records, also into recorded_work_); collect_work() adds them to this iteration's
  // (probe_, and probe_recorded_ for the plan) after the camera pass.
  void add_work(const ProbeWork& w, bool recorded) const;
  void collect_work();

  void camera_path(const Scene& scene, const Iteration& it, const CameraSample& sample, Pcg32& rng,
                   PixelAccumulator& acc, ScratchArena& arena) const;

  // The techniques at a non-delta camera vertex: NEE, connections, merging.
  struct CameraVertex {
    const SurfaceInteraction& si;
    const Bsdf& bsdf;
    Rgb beta;
    const MisSums& mis;
    int depth;
    const VertexGuides& guides;
    const VertexProbabilities& probabilities;  // its next event estimation's
  };
  void vertex_techniques(const Scene& scene, const Iteration& it, const CameraVertex& v,
                         uint64_t light_path, Pcg32& rng, ScratchArena& arena,
                         PixelAccumulator& acc) const;

  void next_event(const Scene& scene, const MisRules& rules, const CameraVertex& v, Pcg32& rng,
                  PixelAccumulator& acc) const;

  // Connections to the vertices of `connections` light paths: the pixel's own, then paths drawn
  // uniformly (each light path is an independent sample, so any choice is unbiased); each
  // connection is one of c samples, hence the 1 / c.
  void connect_to_light_paths(const Scene& scene, const Iteration& it, const MisRules& rules,
                              const CameraVertex& v, uint64_t light_path, Pcg32& rng,
                              ScratchArena& arena, PixelAccumulator& acc) const;

  // beta: the camera vertex's throughput over the connections per vertex. own: light_path is
  // the pixel's own (its rebuilt vertices are kept in acc for the pixel's other camera vertices).
  void connect_to_light_path(const Scene& scene, const MisRules& rules, const CameraVertex& v,
                             Rgb beta, uint64_t light_path, bool own, Pcg32& rng,
                             ScratchArena& arena, PixelAccumulator& acc) const;

  // Merging accepts a photon only if light could have reached the query's surface through it
  // (no leaks through zero-thickness walls):
  //  - it lies within half the radius of the query's tangent plane (a photon on another sheet
  //    of the same mesh, or behind a corner, is not density on this surface);
  //  - it arrived on a side the query's BSDF scatters from (f = 0 otherwise);
  //  - a photon on another shape (mesh or sphere) than the query must see the query: one shadow
  //    ray from the query to a point just off the photon on the side it arrived from. Photons
  //    on the query's own shape are trusted, so the ray is traced only near shape boundaries.
  // Each test only removes photons; at distance 0 (the partition test's merges) all pass.
  void merge(const Scene& scene, const Iteration& it, const MisRules& rules, const CameraVertex& v,
             PixelAccumulator& acc) const;

  // Whether light arriving along wo at the query could be the photon's (a photon on another
  // shape than the query). Each point must lie on the lit side (the side of wo) of the other's
  // surface, within a ten-thousandth of the radius: a photon on the far face of a
  // zero-thickness wall, or a query behind the photon's wall, fails here. Then a shadow ray
  // between the two, each end offset off its own surface to the side of wo, catches a wall
  // between them (a floor continuing under the wall into the next room). The photon's hit
  // record is rebuilt for its normal and error bounds.
  bool photon_visible(const Scene& scene, const SurfaceInteraction& si, uint32_t primitive, Vec3 q,
                      Vec3 wo, float radius) const;

  BidirAlgorithm algorithm_;
  Techniques tech_;
  IntegratorSettings settings_;
  // Whether the MIS densities are the guided mixtures' (GuidingSettings::guided_mis).
  bool guided_mis() const { return tech_.guided && settings_.guiding.guided_mis; }
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
  std::vector<StoredTrack> tracks_;              // per vertex (correlation-aware MIS)
  std::vector<CorrelationEntry> track_entries_;  // their entries
  std::vector<uint32_t> path_begin_;
  HashGrid grid_;
  Image splat_image_;
  // Written by the camera pass (estimate() is const): each pixel by the one task that owns it.
  mutable TechniqueImages techniques_;

  // Statistics.
  uint32_t iterations_ = 0;
  uint64_t vertices_total_ = 0;
  double seconds_total_ = 0;
  double grid_seconds_total_ = 0;    // of seconds_total_, building the hash grid
  double light_seconds_total_ = 0;   // of seconds_total_, tracing light paths (with their splats)
  double camera_seconds_total_ = 0;  // of seconds_total_, tracing camera paths
  double probe_seconds_total_ = 0;   // of seconds_total_, adaptive-vcm's probe iterations
  // adaptive-vcm: thread-seconds of the iterations since the last probe (the last choice's), for
  // the plan's check of its predicted cost.
  double segment_thread_seconds_ = 0;
  // adaptive-vcm with --time: how many iterations those were on this rank, for the probes'
  // measured share of the budget (AdaptivePlan::set_times).
  uint32_t segment_iterations_ = 0;
  ProbeWork work_total_;  // operations counted over all iterations (counts only)
  std::vector<std::string> technique_files_;

  // guided-bpt / guided-vcm: the learned fields, and per-pass pixel moments for their schedule
  // (camera_values_: this iteration's camera estimate per pixel, each written by its task).
  BidirGuiding guiding_;
  InverseVarianceCombiner guided_passes_;
  std::vector<double> pass_end_seconds_;  // when each completed pass ended (statistics)
  mutable std::vector<Rgb> camera_values_;
  std::chrono::steady_clock::time_point start_;

  // adaptive-vcm: the plan, and the work of the current probe iteration.
  mutable AdaptivePlan plan_;
  ProbeWork probe_;           // this iteration's work
  ProbeWork probe_recorded_;  // the camera-pass work of the pixels a probe records
  uint64_t light_rays_ = 0;   // this iteration's light-subpath rays (append_chunk)
  mutable tbb::enumerable_thread_specific<ProbeWork> pixel_work_, recorded_work_;
  // adaptive-vcm's path-tracing iterations (no light paths, not a probe) are rendered by pt's
  // own estimator: the same image in expectation, about 1.25x cheaper than the core's camera
  // subpaths, which carry MIS sums no technique reads. Probes stay in the core (they price
  // every candidate), and so do runs that write technique images.
  std::unique_ptr<PathTracer> path_tracer_;
  uint32_t path_tracing_iterations_ = 0;
  // The pixel means observe_film() was given for the next probe (else the probe reads its film).
  std::vector<float> observed_means_;
  bool observed_ = false;
  // The pixel moments of the iterations that rendered the current choice, and their sum over
  // the ranks that observe_learning_sums() was given for the next probe (empty: read segment_).
  SegmentMoments segment_;
  std::vector<FixedSum> observed_segment_;
  // The probes' sums beside the film, and the weight image() gave them (probe_film.h).
  ProbeFilm probe_film_;
  mutable AdaptivePlan::ProbeWeight probe_weight_;
};

}  // namespace caustica::bidir
