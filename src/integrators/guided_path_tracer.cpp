#include "integrators/guided_path_tracer.h"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <optional>

#include "core/math.h"
#include "film/film.h"
#include "integrators/guide_views.h"
#include "integrators/guided_mixture.h"
#include "integrators/path_vertex.h"
#include "integrators/schedule_report.h"
#include "lights/light.h"
#include "lights/light_sampler.h"
#include "materials/material.h"
#include "scene/scene.h"

namespace caustica {

namespace {

// Records of one path are keyed pixel * kKeysPerPixel + their order along the path (at most two
// per scattering vertex, and at most 255 vertices).
constexpr uint64_t kKeysPerPixel = 512;

// The mixture at a vertex at p: guided where the BSDF has neither delta nor near-specular lobes
// (layered BSDFs are guided whatever their coat: guided_mixture.h), with the distribution and
// selection probability of p's leaf on the side the path arrived from (GuidingField::side_class of
// the geometric normal facing wo); its records go to the leaf of p jittered by the leaf's size (the
// spatial box filter).
Mixture mixture_at(const GuidingField& field, const GuidingSettings& settings, bool learn,
                   const SurfaceInteraction& si, const Bsdf& bsdf, Pcg32& rng) {
  Mixture mix;
  mix.guidable = guidable_bsdf(bsdf);
  if (!mix.guidable) return mix;
  const Vec3 p = si.p;
  const int side = GuidingField::side_class(face_forward(si.ng, si.wo));
  const uint32_t leaf = field.leaf_at(p, side);
  const GuidingField::Guide& guide = field.guide(leaf);
  if (guide.distribution) {
    mix.guide = guide.distribution;
    mix.bsdf_fraction = guide.bsdf_fraction;
  }
  mix.nee_probability = guide.probability[GuidingField::kNextEvent];
  mix.leaf = mix.record_leaf = leaf;
  if (!learn) return mix;
  if (settings.cosine_product) mix.cosine_normal = si.shading.n;
  if (settings.filter) {
    const float ux = rng.next_float(), uy = rng.next_float(), uz = rng.next_float();
    mix.record_leaf = field.jittered_leaf(p, leaf, Vec3(ux, uy, uz), side);
  }
  return mix;
}

// A guided vertex whose incident radiance along wi is recorded once the path is done.
struct GuidedVertex {
  GuidingRecord record;  // radiance and product filled in at the end
  float per_pdf;         // the record's weight along wi over the density wi was sampled with
  Rgb weight;            // f |cos| / pdf
  Rgb beta_after;        // path throughput including this vertex's weight
  Rgb incident;          // estimate of the radiance arriving along wi (Müller et al. 2017)
};

// What one path teaches the field: its guided vertices and their next event samples.
class PathLearning {
 public:
  // weight: the pixels this one stands for (1 in `weight` pixels records; see kMaxRecords).
  PathLearning(ScratchArena& arena, int max_vertices, uint64_t pixel, PixelRecords::Writer records,
               float weight)
      : vertices_(static_cast<GuidedVertex*>(arena.allocate(
            sizeof(GuidedVertex) * size_t(std::max(max_vertices, 1)), alignof(GuidedVertex)))),
        next_events_(static_cast<GuidingRecord*>(arena.allocate(
            sizeof(GuidingRecord) * size_t(std::max(max_vertices, 1)), alignof(GuidingRecord)))),
        records_(records),
        key_(pixel * kKeysPerPixel),
        weight_(weight) {}

  // A contribution c after vertex j is beta_after_j times an estimate of what arrives along its
  // wi; every contribution reaches the vertices before it.
  void contribute(Rgb c) {
    for (int j = 0; j < count_; ++j)
      for (int ch = 0; ch < 3; ++ch)
        if (vertices_[j].beta_after[ch] > 0)
          vertices_[j].incident[ch] += c[ch] / vertices_[j].beta_after[ch];
  }
  void add_vertex(const Mixture& m, const MixtureSample& s, Rgb beta_after) {
    GuidingRecord r = base_record(m, s.pdfs);
    vertices_[count_++] = {r, m.record_weight(s.wi) / s.pdf, s.weight, beta_after, Rgb(0.f)};
  }
  // The next event sample's radiance times its MIS weight over the light density: the light
  // technique's share of the incident radiance's flux estimate.
  void add_next_event(const Mixture& m, const NextEventSeen& seen, const DirectionPdfs& pdfs) {
    GuidingRecord r = base_record(m, pdfs);
    // No selection gradient: the mixture need not find what next event estimation already
    // samples well (its share of direct light); the path records' product holds only the
    // direction sampling's own MIS-weighted share.
    r.guide_pdf = 0;
    const float scale = weight_ * seen.weight / seen.light_pdf;
    r.radiance = seen.Li.luminance() * scale * m.record_weight(seen.wi);
    r.product = (seen.f * seen.Li).luminance() * scale;
    r.statistical_weight = 0;
    if (r.radiance > 0 && std::isfinite(r.radiance)) next_events_[next_event_count_++] = r;
  }
  // Müller et al. 2017, sec. 3.2: each vertex splats L_i / pdf (times |cos| where the guides
  // learn the product with the cosine), an estimate of the flux through the quadrant it lands in.
  // The records go out in key order (the vertices' and the next event samples' interleaved).
  void finish() {
    int e = 0;
    for (int j = 0; j < count_; ++j) {
      GuidedVertex& v = vertices_[j];
      for (; e < next_event_count_ && next_events_[e].key < v.record.key; ++e)
        records_.push(next_events_[e]);
      v.record.radiance = weight_ * v.incident.luminance() * v.per_pdf;
      v.record.product = weight_ * (v.weight * v.incident).luminance();
      if (v.record.radiance > 0 && std::isfinite(v.record.radiance)) records_.push(v.record);
    }
    for (; e < next_event_count_; ++e) records_.push(next_events_[e]);
  }

 private:
  GuidingRecord base_record(const Mixture& m, const DirectionPdfs& pdfs) {
    GuidingRecord r;
    r.key = key_++;
    r.leaf = m.record_leaf;
    r.square = pdfs.square;
    r.bsdf_pdf = pdfs.bsdf;
    r.guide_pdf = pdfs.guide;
    return r;
  }

  GuidedVertex* vertices_;
  GuidingRecord* next_events_;  // kept until finish(), to go out in key order
  int count_ = 0, next_event_count_ = 0;
  PixelRecords::Writer records_;
  uint64_t key_;
  float weight_;
};

}  // namespace

void GuidedPathTracer::prepare(const Scene& scene, Film& film) {
  CameraPathIntegrator::prepare(scene, film);
  field_ = GuidingField(scene.bounds(), settings_.guiding, /*sided=*/true);
  passes_ = InverseVarianceCombiner(scene.camera().width(), scene.camera().height());
  schedule_ = TrainingSchedule(budget_spp(), budget_seconds());
  start_ = std::chrono::steady_clock::now();
  recorded_ = 0;
  pass_end_seconds_.clear();
  peak_record_bytes_ = 0;
  record_stride_ = std::max<uint64_t>(
      1, (film.pixel_count() * kFirstRecordsPerPixel + kMaxRecords - 1) / kMaxRecords);
}

void GuidedPathTracer::render_iteration(const Scene& scene, uint32_t iteration, Film& film) {
  if (iteration == 0) schedule_.starts_pass(0, seconds_since_start());
  iterations_ = iteration + 1;
  if (!schedule_.learning()) {  // rendering: sampling only
    trace_camera_paths(scene, iteration, film);
    if (!film_is_the_image()) passes_.end_iteration();
    end_pass_after(iteration);
    return;
  }
  // Slot pixel / stride: the recorded pixels are stride apart.
  records_.begin_iteration(film.pixel_count() / record_stride_ + 1);
  trace_camera_paths(scene, iteration, film);
  passes_.end_iteration();
  const size_t recorded = records_.size();
  for (std::vector<uint32_t>& counts : vertex_counts_) {
    field_.add_vertex_counts(counts);
    std::fill(counts.begin(), counts.end(), 0);
  }
  for (std::vector<uint32_t>& counts : nee_counts_) {
    field_.add_nee_counts(counts);
    std::fill(counts.begin(), counts.end(), 0);
  }
  field_.splat(records_.runs());
  recorded_ += recorded;
  peak_record_bytes_ =
      std::max(peak_record_bytes_, records_.capacity_bytes() + field_.splat_buffer_bytes());
  // The next iteration records one pixel in k, k from this one's records per pixel: the
  // buffers stay near kMaxRecords at any resolution (deterministic: counts, not threads).
  const uint64_t per_all_pixels = uint64_t(recorded) * record_stride_;
  record_stride_ = std::max<uint64_t>(1, (per_all_pixels + kMaxRecords - 1) / kMaxRecords);
  end_pass_after(iteration);
}

double GuidedPathTracer::seconds_since_start() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void GuidedPathTracer::end_pass_after(uint32_t iteration) {
  if (!schedule_.starts_pass(iteration + 1, seconds_since_start())) return;
  const bool learned = schedule_.ended_learning();
  const int k = schedule_.ended_training_pass();
  const InverseVarianceCombiner::Pass ended = passes_.passes().back();
  schedule_.end_pass(ended.variance, ended.variance_error);
  if (learned) field_.end_pass(k);
  passes_.end_pass();
  pass_end_seconds_.push_back(seconds_since_start());
}

std::span<FixedSum> GuidedPathTracer::sums_over_ranks(bool root) {
  if (!settings_.guiding.inverse_variance) return {};  // the image is the film's
  // Every rank rendered the whole of a pass that teaches (shared_iteration): rank 0's is it.
  if (!root && !schedule_.final_pass()) passes_.clear_current();
  return passes_.current_sums();
}

void GuidedPathTracer::finish(const Scene& scene, Film& film) {
  CameraPathIntegrator::finish(scene, film);
  views_ = guide_views(scene,
                       [&](Vec3 p, int side) { return &field_.sampling(field_.leaf_at(p, side)); });
}

bool GuidedPathTracer::film_is_the_image() const {
  return !settings_.guiding.inverse_variance || (schedule_.final_pass() && !schedule_.guided());
}

Image GuidedPathTracer::image(const Film& film) const {
  if (film_is_the_image()) return film.image();
  Image combined = passes_.image();
  return combined.empty() ? film.image() : combined;
}

Rgb GuidedPathTracer::estimate(const Scene& scene, const CameraSample& sample, Pcg32& rng,
                               ScratchArena& arena, uint64_t*) const {
  const MisHeuristic heuristic = settings_.mis_or(MisHeuristic::Power);
  const bool learn =
      schedule_.learning() && (sample.pixel + sample.iteration) % record_stride_ == 0;
  const bool guided = schedule_.guided();
  if (!learn && !guided) {  // an unguided pass: exactly pt's estimator
    const Rgb L = unguided_.radiance(scene, sample.ray, rng, arena);
    if (!film_is_the_image()) passes_.add(sample.pixel, L * sample.filter_weight);
    return L;
  }
  // Rendering passes and unrecorded pixels learn nothing: no per-thread buffers are looked up.
  std::optional<PathLearning> learning;
  std::vector<uint32_t>* vertex_counts = nullptr;
  std::vector<uint32_t>* nee_counts = nullptr;
  if (learn) {
    learning.emplace(arena, settings_.max_depth, sample.pixel,
                     records_.writer(sample.pixel / record_stride_), float(record_stride_));
    vertex_counts = &vertex_counts_.local();
    if (vertex_counts->size() != field_.leaf_count()) vertex_counts->assign(field_.leaf_count(), 0);
    nee_counts = &nee_counts_.local();
    if (nee_counts->size() != 2 * field_.leaf_count())
      nee_counts->assign(2 * field_.leaf_count(), 0);
  }
  Rgb L(0.f), beta(1.f);
  Rgb rr_beta(1.f);  // the throughput of BSDF sampling, for Russian roulette
  Ray ray = sample.ray;
  int depth = 0;
  bool specular_bounce = false;
  float eta_scale = 1;  // refractions sampled by the BSDF, undone for Russian roulette
  float prev_pdf = 0;   // density of the direction that produced `ray` (mixture where guided)
  Vec3 prev_p;
  float prev_nee = 1;  // the probability of next event estimation at prev_p
  SegmentEnd start;    // the first end of `ray`, for media (the camera's names none)

  auto add = [&](Rgb c) {
    L += c;
    if (learn) learning->contribute(c);
  };
  auto add_emission = [&](const SurfaceInteraction* hit) {
    add_emission_seen(
        scene, ray, hit, depth == 0 || specular_bounce, prev_pdf, prev_p, heuristic,
        [&](Rgb Le, float w) { add(beta * Le * w); }, prev_nee);
  };

  for (;;) {
    SurfaceInteraction si;
    Bsdf bsdf;
    if (!next_scattering_vertex(scene, ray, start, beta, arena, &si, &bsdf, add_emission)) break;
    if (depth++ == settings_.max_depth) break;

    const Vec3 wo = si.wo;
    const Mixture mix = mixture_at(field_, settings_.guiding, learn, si, bsdf, rng);
    // Next event estimation asks for the mixture density toward the light (not for a delta
    // light); what it evaluated is kept for the record.
    DirectionPdfs nee_pdfs;
    bool nee_evaluated = false;
    auto mixture_pdf = [&](Vec3 wi) {
      nee_pdfs = mix.evaluate(bsdf, wo, wi);
      nee_evaluated = true;
      return mix.pdf(nee_pdfs);
    };

    // With the leaf's probability q (1 unless it saw no light: GuidingSettings::nee_floor), u_light
    // below q runs it, rescaled to pick the light (q = 1: always, with the same numbers).
    float u_light = rng.next_float();
    const Vec2 u = rng.next_2d();
    const float q = mix.nee_probability;
    NextEventSeen seen;
    if (u_light < q) {
      if (q < 1) u_light = std::min(u_light / q, kOneMinusEpsilon);
      add(direct_light_mis(
          scene, si, bsdf, beta, u_light, u, mixture_pdf,
          [&](float a, float b) { return mis_weight(heuristic, a, b); }, &seen, q));
      if (learn && mix.guidable && !scene.light_sampler().empty()) {  // guidable: not delta
        ++(*nee_counts)[2 * mix.leaf];
        (*nee_counts)[2 * mix.leaf + 1] += !seen.Li.is_black();
      }
    }
    if (learn && mix.guidable && !seen.Li.is_black())
      learning->add_next_event(mix, seen,
                               nee_evaluated ? nee_pdfs : mix.evaluate(bsdf, wo, seen.wi));

    const float uc = rng.next_float();
    const Vec2 u_dir = rng.next_2d();
    const float u_technique = rng.next_float();
    const auto s = sample_mixture(bsdf, wo, mix, u_technique, uc, u_dir);
    if (!s) break;
    eta_scale *= s->eta2;
    beta *= s->weight;
    if (learn && mix.guidable) {
      (*vertex_counts)[mix.record_leaf] += uint32_t(record_stride_);
      // A layered BSDF's delta sample (its smooth coat) has no density to record.
      if (!s->specular) learning->add_vertex(mix, *s, beta);
    }
    prev_pdf = s->pdf;
    prev_nee = q;
    specular_bounce = s->specular;
    prev_p = si.p;
    start = si.medium_toward(s->wi);
    ray = si.spawn_ray(s->wi);
    if (beta.is_black()) break;
    rr_beta *= s->bsdf_weight;
    if (!survives_guided_roulette(beta, rr_beta, eta_scale, depth, rng)) break;
  }
  if (learn) learning->finish();
  passes_.add(sample.pixel, L * sample.filter_weight);
  return L;
}

void GuidedPathTracer::report(nlohmann::json& stats) const {
  nlohmann::json g;
  report_schedule(schedule_, g);
  g["spatial_leaves"] = field_.leaf_count();
  g["spatial_nodes"] = field_.spatial_node_count();
  g["quadtree_nodes"] = field_.quadtree_node_count();
  g["guiding_bytes"] = field_.memory_bytes();
  g["guiding_max_bytes"] = settings_.guiding.max_bytes;
  g["record_buffer_peak_bytes"] = peak_record_bytes_;
  g["record_pixel_stride_last"] = record_stride_;
  g["radiance_samples_recorded"] = recorded_;
  g["mean_bsdf_fraction"] = field_.mean_bsdf_fraction();
  g["nee_floor"] = settings_.guiding.nee_floor;
  g["nee_reduced_leaves"] = field_.reduced_nee_leaves();
  report_passes(passes_, !film_is_the_image(), pass_end_seconds_, seconds_since_start(), g);
  if (settings_.guiding.inverse_variance && film_is_the_image() &&
      schedule_.rendering_from() >= 0) {
    // The unguided rest after a lost trial went to the film alone: no variance of its own.
    const double begin = pass_end_seconds_.empty() ? 0.0 : pass_end_seconds_.back();
    int64_t before = 0;
    for (const InverseVarianceCombiner::Pass& p : passes_.passes()) before += p.samples;
    g["passes"].push_back({{"spp", int64_t(iterations_) - before},
                           {"variance", -1.0},
                           {"variance_error", -1.0},
                           {"seconds", std::max(0.0, seconds_since_start() - begin)}});
  }
  if (!views_.is_null()) g["views"] = views_;
  stats["guiding"] = g;
}

}  // namespace caustica
