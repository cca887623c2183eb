// Light subpaths of the bidirectional core (bidir_core.h): traced in chunks, their non-delta
// vertices stored (light_vertex.h) and, for light tracing, connected to the lens.
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <optional>

#include "film/film.h"
#include "integrators/bidir/bidir_core.h"
#include "integrators/bidir/subpath_records.h"
#include "integrators/bidir/subpath_step.h"
#include "lights/light.h"
#include "lights/light_sampler.h"
#include "materials/material.h"
#include "scene/scene.h"

namespace caustica::bidir {

namespace {

Ray ray_leaving_light(const LightLeSample& le, const Light& light) {
  if (light.type() == LightType::Area) {
    // The emission point lies on the light's surface: nudge it to the emitting side.
    const Vec3 side = face_forward(le.n, le.dir);
    const float eps = 1e-4f * std::max(1.f, max_component(abs(le.p)));
    return {le.p + side * eps, le.dir, kInfinity};
  }
  return {le.p, le.dir, kInfinity};
}

}  // namespace

void BidirIntegrator::trace_light_paths(const Scene& scene, const Iteration& it, Film& film) {
  const auto start = std::chrono::steady_clock::now();
  vertices_.clear();
  tracks_.clear();
  track_entries_.clear();
  path_begin_.resize(it.plan.light_paths + 1);
  light_chunk_seconds_ = 0;
  light_rays_ = 0;
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
    tbb::parallel_pipeline(tokens,
                           tbb::make_filter<void, uint64_t>(tbb::filter_mode::serial_in_order,
                                                            [&](tbb::flow_control& fc) -> uint64_t {
                                                              if (next_chunk == chunk_count_)
                                                                fc.stop();
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

void BidirIntegrator::trace_chunk(const Scene& scene, const Iteration& it, uint64_t c,
                                  LightChunk& chunk) const {
  thread_local ScratchArena arena;
  chunk.vertices.clear();
  chunk.tracks.clear();
  chunk.track_entries.clear();
  chunk.path_ends.clear();
  chunk.splats.clear();
  chunk.splat_terms.clear();
  chunk.nonfinite = 0;
  chunk.rays = 0;
  const auto chunk_start = std::chrono::steady_clock::now();
  chunk.first_path = c * chunk_paths_;
  const uint64_t last = std::min<uint64_t>(chunk.first_path + chunk_paths_, it.plan.light_paths);
  for (uint64_t path = chunk.first_path; path < last; ++path) {
    arena.reset();
    trace_light_path(scene, it, path, chunk, arena);
    chunk.path_ends.push_back(uint32_t(chunk.vertices.size()));
  }
  chunk.seconds = it.plan.probe && settings_.bidir.measured_costs ? seconds_since(chunk_start) : 0;
}

void BidirIntegrator::append_chunk(const Iteration& it, const LightChunk& chunk) {
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
  if (!chunk.tracks.empty()) {
    const uint32_t entries_base = uint32_t(track_entries_.size());
    for (StoredTrack t : chunk.tracks) {
      if (t.count > StoredTrack::kInline) t.first += entries_base;
      tracks_.push_back(t);
    }
    track_entries_.insert(track_entries_.end(), chunk.track_entries.begin(),
                          chunk.track_entries.end());
  }
  for (size_t i = 0; i < chunk.path_ends.size(); ++i)
    path_begin_[chunk.first_path + i] = base + (i ? chunk.path_ends[i - 1] : 0);
  light_chunk_seconds_ += chunk.seconds;
  light_rays_ += chunk.rays;
  size_t recorded = 0;  // the splats in recorded pixels, whose terms the chunk kept
  for (const Splat& s : chunk.splats) {
    splat_image_[s.pixel] += s.value;
    if (techniques_.enabled()) techniques_.add(s.technique, s.pixel, s.value);
    if (it.plan.records(s.pixel))
      plan_.add_light_trace(s.pixel, scalar(s.value), &chunk.splat_terms[recorded++],
                            it.rules_probe.counts());
  }
}

StoredTrack BidirIntegrator::store_track(const CorrelationTrack& track,
                                         std::vector<CorrelationEntry>& pool) {
  StoredTrack t;
  t.own_total = track.own_total;
  t.seg_cos = track.seg_cos;
  t.seg_dist2 = track.seg_dist2;
  t.count = uint32_t(track.count);
  if (t.count > StoredTrack::kInline) {
    t.first = uint32_t(pool.size());
    pool.insert(pool.end(), track.entries, track.entries + track.count);
  } else {
    std::copy_n(track.entries, t.count, t.inline_entries);
  }
  return t;
}

void BidirIntegrator::load_track(uint32_t index, CorrelationTrack* out) const {
  const StoredTrack& t = tracks_[index];
  out->count = int(t.count);
  // Techniques only read a light vertex's entries (MisRules::correlated_merges).
  out->entries = t.count > StoredTrack::kInline
                     ? const_cast<CorrelationEntry*>(track_entries_.data()) + t.first
                     : const_cast<CorrelationEntry*>(t.inline_entries);
  out->own_total = t.own_total;
  out->seg_cos = t.seg_cos;
  out->seg_dist2 = t.seg_dist2;
}

void BidirIntegrator::trace_light_path(const Scene& scene, const Iteration& it, uint64_t path,
                                       LightChunk& chunk, ScratchArena& arena) const {
  const LightSampler& sampler = scene.light_sampler();
  if (sampler.empty()) return;
  Pcg32 rng = Pcg32::for_sample(path, it.index, hash_combine(settings_.seed, 0x11947ull));
  float pmf;
  const Light* light = sampler.sample(rng.next_float(), &pmf);
  const Vec2 u_pos = rng.next_2d(), u_dir = rng.next_2d();
  if (!light || !(pmf > 0)) return;
  const auto le = light->sample_le(u_pos, u_dir);
  if (!le || !(le->pdf_pos > 0) || !(le->pdf_dir > 0) || le->radiance.is_black()) return;
  if (tech_.light_origin && light->type() == LightType::Area)
    connect_emission_to_camera(scene, it, *light, pmf, *le, path, chunk);
  const float emission_pdf = pmf * le->pdf_pos * le->pdf_dir;
  Rgb beta = le->radiance * (le->cos_at_light / emission_pdf);
  Rgb rr_beta = beta;  // the throughput BSDF sampling alone would have (guided roulette)
  const float beta_start = beta.max_component();
  const int max_depth = settings_.max_depth;

  Ray ray = ray_leaving_light(*le, *light);
  // guided-bpt / guided-vcm learning importance from light subpaths: what each guided vertex's
  // later vertices saw of the camera (subpath_records.h, with importance).
  std::optional<SubpathRecords> importance_records;
  if (tech_.guided && guiding_.records_importance_path(path))
    importance_records.emplace(arena, max_depth);
  Rgb seen(0.f);  // the unweighted lens connections so far
  MisSums mis;
  // Correlation-aware MIS: the subpath's merges one by one (mis.corr points here).
  std::optional<OwnedCorrelationTrack> track;
  if (it.rules.correlated()) track.emplace();
  float segment = 0;  // distance since the previous real vertex (interfaces are skipped)
  int depth = 0;
  // Absorbing media (geometry/medium.h): each segment's transmittance goes into beta.
  const bool media = scene.has_media();
  SegmentEnd start = media ? light->medium_toward(le->n, ray.d) : SegmentEnd{};
  for (;;) {
    SurfaceInteraction si;
    ++chunk.rays;
    if (!scene.intersect(ray, &si)) break;
    segment += si.t;
    if (media) beta *= scene.transmittance(start, si.medium_toward(-ray.d), si.t);
    Bsdf bsdf;
    if (si.material) bsdf = si.material->bsdf(si, arena);
    if (!bsdf.valid()) {
      start = si.medium_toward(ray.d);
      ray = si.spawn_ray(ray.d);
      continue;
    }
    ++depth;
    if (depth == 1) {
      mis = light_subpath_start(it.rules, *light, pmf, *le, si, segment, track ? &*track : nullptr);
    } else {
      it.rules.hit(mis, segment * segment, geometric_cos(si, si.wo));
    }
    segment = 0;
    if (depth > max_depth) break;

    const VertexGuides guides = tech_.guided ? guiding_.at(si.p, si.ng, bsdf) : VertexGuides{};
    const VertexProbabilities probabilities = tech_.guided && !bsdf.is_delta()
                                                  ? guiding_.probabilities_at(si.p, si.ng)
                                                  : VertexProbabilities{};
    // dVCM at y1 stands for next event estimation from y1 toward the light (mis.h, scale_vcm).
    if (depth == 1 && probabilities)
      it.rules.scale_vcm(mis, probabilities.of(GuidingField::kNextEvent, si.wo));
    if (!bsdf.is_delta()) {
      if (stores_vertices()) {
        chunk.vertices.push_back(
            pack_light_vertex({si.p, si.wo, scene.primitive_index(si), depth, beta, mis}));
        if (track) chunk.tracks.push_back(store_track(*track, chunk.track_entries));
      }
      if (tech_.light_to_camera) {
        const Rgb c = connect_to_camera(scene, it, si, bsdf, guided_mis() ? guides : kUnguided,
                                        probabilities, beta, mis, depth, rng, chunk);
        if (c.is_finite()) seen += c;
      }
    }
    if (depth + 1 > max_depth) break;

    const auto step = scatter_subpath(it.rules, mis, si, bsdf, guides, TransportMode::Importance,
                                      rng, beta, rr_beta, guided_mis());
    if (!step) break;
    // dVCM at the next vertex stands for this vertex's connection toward it.
    if (probabilities && !step->specular)
      it.rules.scale_vcm(mis, probabilities.of(GuidingField::kConnection, step->wi));
    if (importance_records && !step->specular && BidirGuiding::guidable(bsdf)) {
      importance_records->gained(seen);
      importance_records->add({si.p, si.ng, step->wi, depth, bsdf.abs_cos(step->wi) / step->pdf,
                               step->weight, step->bsdf_pdf, step->guide_pdf, beta, Rgb(0.f)});
    }
    if (beta.is_black()) break;
    start = si.medium_toward(step->wi);
    ray = si.spawn_ray(step->wi);
    // Russian roulette on the throughput relative to the emitted one (importance carries no
    // radiance scaling at refractions, so no eta correction); guided, on the larger of it and
    // BSDF sampling's (path_vertex.h, survives_guided_roulette).
    const float rr = (tech_.guided ? std::max(beta.max_component(), rr_beta.max_component())
                                   : beta.max_component()) /
                     beta_start;
    if (rr < 1 && depth > 1) {
      const float q = std::max(0.f, 1 - rr);
      if (rng.next_float() < q) break;
      beta = beta / (1 - q);
      rr_beta = rr_beta / (1 - q);
    }
  }
  if (importance_records)
    importance_records->finish(
        seen, [&](const SubpathRecords::Vertex& v, float importance, float product) {
          guiding_.record_light_importance(path, v, importance, product);
        });
}

template <typename ValueOf, typename TermsOf>
bool BidirIntegrator::splat_lens_connection(const Camera& camera, const Iteration& it, Vec2 raster,
                                            uint32_t technique, const ValueOf& value_of,
                                            const TermsOf& terms_of, LightChunk& chunk) const {
  const size_t first_splat = chunk.splats.size();
  filter_.for_each_pixel(raster, camera.width(), camera.height(),
                         [&](int x, int y, const FilterSample& fs) {
                           const uint32_t pixel = uint32_t(y * camera.width() + x);
                           if (tech_.adaptive && !it.plan.takes_splats(pixel))
                             return;  // pt's or ppm's estimator alone there
                           const MisRules& rules = it.rules_at(pixel);
                           const TechniqueTerms terms = terms_of(rules, fs.pdf);
                           const float w = tech_.unweighted ? 1.f : terms.weight(rules.counts());
                           const Rgb value = value_of(w) * (fs.weight * fs.pdf);
                           if (value.is_black()) return;
                           if (!value.is_finite()) {
                             ++chunk.nonfinite;
                             return;
                           }
                           chunk.splats.push_back({pixel, technique, value});
                           // The plan prices the recorded pixels' splats (append_chunk).
                           if (it.plan.records(pixel)) chunk.splat_terms.push_back(terms);
                         });
  return chunk.splats.size() > first_splat;
}

bool BidirIntegrator::splat_can_land(const Camera& camera, const Iteration& it, Vec2 raster) const {
  if (!tech_.adaptive) return true;
  const auto [x0, x1, y0, y1] = filter_.candidate_pixels(raster, camera.width(), camera.height());
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x)
      if (it.plan.takes_splats(size_t(y) * size_t(camera.width()) + size_t(x))) return true;
  return false;
}

void BidirIntegrator::connect_emission_to_camera(const Scene& scene, const Iteration& it,
                                                 const Light& light, float pmf,
                                                 const LightLeSample& le, uint64_t path,
                                                 LightChunk& chunk) const {
  const Camera& camera = scene.camera();
  // A stream of its own: the light subpaths draw the numbers they drew without this technique.
  if (it.plan.splats_nowhere) return;
  Pcg32 rng = Pcg32::for_sample(path, it.index, hash_combine(settings_.seed, 0x1e4ull));
  const auto cs = camera.sample_wi(le.p, rng.next_2d());
  if (!cs || !(cs->importance > 0) || !splat_can_land(camera, it, cs->raster)) return;
  const Rgb radiance = light.radiance(le.p, le.n, {}, cs->wi);
  if (radiance.is_black()) return;
  const float pos_pdf = pmf * le.pdf_pos;
  const LensConnection lens = lens_connection_of_emission(camera, le.p, le.n, cs->p_lens);
  // Le G We / (pmf pdf_pos) per light path, in connect_to_camera's units (G = cos_light / pdf_w
  // with pdf_w the lens point's solid-angle density at the light point).
  const float scale = lens.cos_at_vertex * cs->importance * float(camera.pixel_count()) /
                      (cs->pdf_w * float(it.plan.light_paths) * pos_pdf);
  // The shadow ray before the splats and their MIS terms (up to 16 pixels under a wide filter).
  const Vec3 o =
      le.p + face_forward(le.n, cs->wi) * (1e-4f * std::max(1.f, max_component(abs(le.p))));
  const Rgb seen = radiance * scene.visibility({o, cs->p_lens - o, 1.f - 1e-4f},
                                               light.medium_toward(le.n, cs->wi), {});
  if (seen.is_black()) return;
  splat_lens_connection(
      camera, it, cs->raster, TechniqueImages::key(false, 1, 1),
      [&](float w) { return seen * (scale * w); },
      [&](const MisRules& rules, float raster_density) {
        return terms_light_origin_to_camera(rules, lens, pos_pdf, raster_density);
      },
      chunk);
}

Rgb BidirIntegrator::connect_to_camera(const Scene& scene, const Iteration& it,
                                       const SurfaceInteraction& si, const Bsdf& bsdf,
                                       const VertexGuides& guides,
                                       const VertexProbabilities& probabilities, Rgb beta,
                                       const MisSums& mis, int depth, Pcg32& rng,
                                       LightChunk& chunk) const {
  const Camera& camera = scene.camera();
  const Vec2 u_lens = rng.next_2d();  // drawn also when skipped: the stream stays as it was
  if (it.plan.splats_nowhere) return Rgb(0.f);
  const auto cs = camera.sample_wi(si.p, u_lens);
  if (!cs || !(cs->importance > 0)) return Rgb(0.f);
  // Before the BSDF: adaptive-vcm's vertices are unguided (q = 1 below draws no number), so
  // skipping here leaves every random stream as it was.
  if (!splat_can_land(camera, it, cs->raster)) return Rgb(0.f);
  const Rgb f = bsdf.f(si.wo, cs->wi, TransportMode::Importance) * bsdf.abs_cos(cs->wi);
  if (f.is_black()) return Rgb(0.f);
  // Taken with the vertex's learned probability toward the lens (technique_probabilities.h).
  const float q = probabilities.of(GuidingField::kLensConnection, cs->wi);
  if (q < 1 && rng.next_float() >= q) return Rgb(0.f);
  // Pixel importance is pixel_count * We * f(r - c_p) / integral f; each pixel is estimated by
  // N light paths. Every pixel whose filter support holds the raster point r gets a splat,
  // MIS-weighted against its own camera technique (raster density pdf(r - c_p)).
  const float scale =
      cs->importance * float(camera.pixel_count()) / (cs->pdf_w * float(it.plan.light_paths));
  // The shadow ray before the lens geometry's densities (a coated BSDF's reverse density is a
  // random walk) and the splats' MIS terms: the same splats are made.
  const Rgb tr = scene.visibility(si.spawn_ray_to(cs->p_lens), si.medium_toward(cs->wi), {});
  const bool occluded = tr.is_black();  // through media too
  if (probabilities && guiding_.counts_techniques())
    guiding_.count_technique(GuidingField::kLensConnection, probabilities.leaf_toward(cs->wi),
                             !occluded);
  if (occluded) return Rgb(0.f);
  beta *= tr;
  const LensConnection lens = lens_connection(camera, si, bsdf, si.wo, cs->p_lens, guides);
  const float scale_taken = scale / q;
  const bool splatted = splat_lens_connection(
      camera, it, cs->raster, TechniqueImages::key(false, depth + 1, 1),
      [&](float w) { return beta * f * (scale_taken * w); },
      [&](const MisRules& rules, float raster_density) {
        TechniqueTerms terms = terms_light_to_camera(rules, lens, mis, raster_density);
        terms.own_factor = rules.mis(q);
        return terms;
      },
      chunk);
  return splatted ? beta * f * scale_taken : Rgb(0.f);
}

}  // namespace caustica::bidir
