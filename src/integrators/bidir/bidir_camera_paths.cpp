// Camera subpaths of the bidirectional core (bidir_core.h): emitter hits, next event
// estimation, connections to light subpaths and merging with light vertices, MIS-weighted.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <utility>

#include "integrators/bidir/bidir_core.h"
#include "integrators/bidir/subpath_records.h"
#include "integrators/bidir/subpath_step.h"
#include "integrators/path_vertex.h"
#include "lights/light.h"
#include "lights/light_sampler.h"
#include "materials/material.h"
#include "scene/scene.h"

namespace caustica::bidir {

Rgb BidirIntegrator::estimate(const Scene& scene, const CameraSample& sample, Pcg32& rng,
                              ScratchArena& arena, uint64_t* nonfinite) const {
  const Iteration& it = current_;
  // A path-traced pixel gets no light-tracing splat (connect_to_camera): pt's estimator alone.
  const bool path_traces = tech_.adaptive && it.plan.path_traces(sample.pixel);
  if (path_tracer_ && path_traces) return path_tracer_->radiance(scene, sample.ray, rng, arena);
  PixelAccumulator acc;
  acc.pixel = sample.pixel;
  acc.filter_weight = sample.filter_weight;
  acc.stops = tech_.adaptive && it.plan.stops(sample.pixel);
  if (techniques_.enabled()) acc.techniques = &techniques_;
  const bool records = it.plan.records(sample.pixel);
  acc.rules = path_traces ? &it.rules_camera_only : &it.rules_at(sample.pixel);
  if (records) {
    acc.plan = &plan_;
    acc.candidate_sums = plan_.pixel_start(sample.pixel);
  }
  // The clock is read only where it is used (a clock read per pixel was 0.6% of vcm's profile).
  const bool timed = records && settings_.bidir.measured_costs;
  const auto start =
      timed ? std::chrono::steady_clock::now() : std::chrono::steady_clock::time_point{};
  camera_path(scene, it, sample, rng, acc, arena);
  *nonfinite += acc.nonfinite;
  if (records) {
    plan_.pixel_end(sample.pixel, acc.candidate_sums, acc.work.camera_vertices);
    if (timed) acc.work.camera_seconds = seconds_since(start);
  }
  add_work(acc.work, records);
  if (tech_.guided) camera_values_[sample.pixel] = acc.sum * acc.filter_weight;
  return acc.sum;
}

void BidirIntegrator::add_work(const ProbeWork& w, bool recorded) const {
  auto add = [&](ProbeWork& mine) {
    add_counts(mine, w);  // a pixel's work has no light paths or light vertices
    mine.camera_seconds += w.camera_seconds;
    mine.connect_seconds += w.connect_seconds;
    mine.merge_seconds += w.merge_seconds;
  };
  add(pixel_work_.local());
  if (recorded) add(recorded_work_.local());
}

void BidirIntegrator::collect_work() {
  // The counts are integers held in doubles, exact in any order; the seconds (measured costs
  // only) are not reproducible anyway.
  auto collect = [](tbb::enumerable_thread_specific<ProbeWork>& per_thread, ProbeWork& total) {
    for (ProbeWork& w : per_thread) {
      add_counts(total, w);
      total.camera_seconds += w.camera_seconds;
      total.connect_seconds += w.connect_seconds;
      total.merge_seconds += w.merge_seconds;
      w = {};
    }
  };
  collect(pixel_work_, probe_);
  collect(recorded_work_, probe_recorded_);
}

void BidirIntegrator::camera_path(const Scene& scene, const Iteration& it,
                                  const CameraSample& sample, Pcg32& rng, PixelAccumulator& acc,
                                  ScratchArena& arena) const {
  const Camera& camera = scene.camera();
  const LightSampler& lights = scene.light_sampler();
  const uint64_t pixel = sample.pixel;
  Ray ray = sample.ray;
  const float pdf_camera = camera_pdf_w(camera, ray.o, ray.d, sample.filter_pdf);
  if (!(pdf_camera > 0)) return;
  const MisRules& rules = *acc.rules;
  MisSums mis = rules.camera_start(pdf_camera);
  // Correlation-aware MIS: the subpath's merges one by one, for `mis` (track) and for the sums
  // at the current hit (track_at_hit); the two swap roles when a hit becomes the vertex (mis.h,
  // CorrelationTrack).
  std::optional<OwnedCorrelationTrack> tracks[2];
  CorrelationTrack *track = nullptr, *track_at_hit = nullptr;
  if (rules.correlated()) {
    track = &tracks[0].emplace();
    track_at_hit = &tracks[1].emplace();
    rules.correlation_camera_start(*track, pdf_camera);
    mis.corr = track;
  }
  const int max_depth = settings_.max_depth;
  const uint64_t light_path = it.light_path_of.light_path(pixel);

  Rgb beta(1.f);
  Rgb rr_beta(1.f);  // the throughput BSDF sampling alone would have (guided roulette)
  // The probability of next event estimation at the previous vertex toward this ray's hit
  // (technique_probabilities.h): an emitter hit's weight counts that technique with it.
  float nee_probability_before = 1;
  Vec3 prev_p = ray.o;
  int depth = 0;              // surface vertices so far
  bool specular_path = true;  // every bounce so far was specular
  float segment = 0;
  float eta_scale = 1;
  bool through_interface = false;  // the ray passed a material without a BSDF here
  // Absorbing media (geometry/medium.h): each segment's transmittance goes into beta.
  const bool media = scene.has_media();
  SegmentEnd start;  // the first end of `ray` (the camera's names no medium)
  // guided-bpt / guided-vcm learning radiance from camera subpaths: this pixel's records.
  std::optional<SubpathRecords> radiance_records;
  if (tech_.guided && guiding_.records_radiance_pixel(pixel))
    radiance_records.emplace(arena, max_depth);
  // Emitters: MIS-weighted when connections take part, else only via delta-only chains. An
  // area light seen straight from the lens is weighted against the light subpaths' emission
  // points connected to the lens, unless the ray passed a material without a BSDF there (that
  // connection's shadow ray stops at it; it passes surfaces without a material).
  TechniqueTerms terms;
  bool weighted = false;  // the last emitter weight came from terms
  auto emitter_weight = [&](const Light& light, const SurfaceInteraction* hit, const MisSums& m) {
    weighted = false;
    if (acc.stops) return specular_path ? 1.f : 0.f;  // ppm's: no light-tracing splat here
    if (depth == 0) {
      if (!hit || !tech_.light_origin || through_interface || light.type() != LightType::Area)
        return 1.f;
      weighted = true;
      terms = terms_light_seen_from_lens(rules, light, lights.pmf(&light), *hit, m);
      return terms.weight(rules.counts());
    }
    if (!tech_.connect) return specular_path ? 1.f : 0.f;
    weighted = true;
    terms = terms_emitter_hit(rules, light, lights.pmf(&light), prev_p, ray.d, hit, m,
                              nee_probability_before);
    return terms.weight(rules.counts());
  };

  for (;;) {
    SurfaceInteraction si;
    if (!scene.intersect(ray, &si)) {
      if (media) beta *= scene.transmittance(start, {}, kInfinity);
      for_each_emitter_seen(scene.infinite_lights(), ray, nullptr, [&](const Light& l, Rgb Le) {
        const float w = emitter_weight(l, nullptr, mis);
        if (w > 0) acc.add(false, 0, depth + 2, beta * Le * w, weighted ? &terms : nullptr);
      });
      break;
    }
    segment += si.t;
    if (media) beta *= scene.transmittance(start, si.medium_toward(-ray.d), si.t);
    Bsdf bsdf;
    if (si.material) bsdf = si.material->bsdf(si, arena);
    MisSums at_hit = mis;
    if (track) {
      track_at_hit->assign(*track);
      at_hit.corr = track_at_hit;
    }
    rules.hit(at_hit, segment * segment, geometric_cos(si, si.wo));

    for_each_emitter_seen(scene.infinite_lights(), ray, &si, [&](const Light& l, Rgb Le) {
      const float w = emitter_weight(l, &si, at_hit);
      if (w > 0) acc.add(false, 0, depth + 2, beta * Le * w, weighted ? &terms : nullptr);
    });
    if (!bsdf.valid()) {
      start = si.medium_toward(ray.d);
      ray = si.spawn_ray(ray.d);
      // Shadow rays pass surfaces without a material (Scene::shadow_transmittance) but stop at
      // a material that has no BSDF here (a mix with an interface).
      if (si.material) through_interface = true;
      continue;
    }
    ++depth;
    mis = at_hit;  // with corr = track_at_hit, which becomes the track
    std::swap(track, track_at_hit);
    segment = 0;
    if (depth > max_depth) break;

    const bool delta = bsdf.is_delta();
    ++acc.work.camera_vertices;
    if (specular_path) ++acc.work.stop_camera_vertices;  // photon mapping would come this far
    const VertexGuides guides = tech_.guided ? guiding_.at(si.p, si.ng, bsdf) : VertexGuides{};
    const VertexProbabilities probabilities = tech_.guided && !delta
                                                  ? guiding_.probabilities_at(si.p, si.ng, &guides)
                                                  : VertexProbabilities{};
    // dVCM here stands for the technique whose light subpath ends at this vertex and connects
    // toward wo: to the lens at the first vertex, else to the vertex before (mis.h, scale_vcm).
    if (probabilities)
      rules.scale_vcm(
          mis, probabilities.of(
                   mis.first ? GuidingField::kLensConnection : GuidingField::kConnection, si.wo));
    if (!delta) {
      vertex_techniques(
          scene, it, {si, bsdf, beta, mis, depth, guided_mis() ? guides : kUnguided, probabilities},
          light_path, rng, arena, acc);
      // Importance arriving straight from the lens (directly or through specular bounces only)
      // is what light tracing connects to; a light subpath scattered toward it finds nothing.
      if (tech_.guided && !specular_path && guiding_.records_pixel(pixel))
        guiding_.record_camera_vertex(pixel, depth, si.p, si.ng, si.wo, beta);
    }

    const auto step = scatter_subpath(rules, mis, si, bsdf, guides, TransportMode::Radiance, rng,
                                      beta, rr_beta, guided_mis());
    if (!step) break;
    nee_probability_before =
        probabilities ? probabilities.of(GuidingField::kNextEvent, step->wi) : 1.f;
    if (radiance_records && !step->specular && BidirGuiding::guidable(bsdf)) {
      radiance_records->gained(acc.sum);  // what this vertex's techniques found is not its own
      radiance_records->add({si.p, si.ng, step->wi, depth, bsdf.abs_cos(step->wi) / step->pdf,
                             step->weight, step->bsdf_pdf, step->guide_pdf, beta, Rgb(0.f)});
    }
    // PPM / lt: the non-delta part of this vertex was estimated by merging (or belongs to light
    // tracing); only its delta lobes carry the camera path on.
    if ((tech_.camera_stops || acc.stops) && !delta && !step->specular) break;
    specular_path = specular_path && step->specular;
    eta_scale *= sqr(step->eta);
    if (beta.is_black()) break;
    prev_p = si.p;
    start = si.medium_toward(step->wi);
    ray = si.spawn_ray(step->wi);
    if (tech_.guided ? !survives_guided_roulette(beta, rr_beta, eta_scale, depth, rng)
                     : !survives_russian_roulette(beta, eta_scale, depth, rng))
      break;
  }
  if (radiance_records)
    radiance_records->finish(acc.sum,
                             [&](const SubpathRecords::Vertex& v, float radiance, float product) {
                               guiding_.record_camera_radiance(pixel, v, radiance, product);
                             });
}

void BidirIntegrator::vertex_techniques(const Scene& scene, const Iteration& it,
                                        const CameraVertex& v, uint64_t light_path, Pcg32& rng,
                                        ScratchArena& arena, PixelAccumulator& acc) const {
  const MisRules& rules = *acc.rules;
  const bool timed = acc.plan && settings_.bidir.measured_costs;
  ++acc.work.nondelta_camera_vertices;
  if (acc.stops) {  // ppm's estimator: merging alone, unweighted
    merge(scene, it, rules, v, acc);
    return;
  }
  if (tech_.connect) {
    next_event(scene, rules, v, rng, acc);
    const auto t0 = timed ? std::chrono::steady_clock::now() : Clock::time_point{};
    connect_to_light_paths(scene, it, rules, v, light_path, rng, arena, acc);
    if (timed) acc.work.connect_seconds += seconds_since(t0);
  }
  if (tech_.merge && it.plan.merges(acc.pixel)) {
    const auto t0 = timed ? std::chrono::steady_clock::now() : Clock::time_point{};
    merge(scene, it, rules, v, acc);
    if (timed) acc.work.merge_seconds += seconds_since(t0);
  }
}

void BidirIntegrator::next_event(const Scene& scene, const MisRules& rules, const CameraVertex& v,
                                 Pcg32& rng, PixelAccumulator& acc) const {
  const float u_light = rng.next_float();
  const Vec2 u = rng.next_2d();
  const auto d = sample_direct_light(scene, v.si, v.bsdf, u_light, u);
  if (!d) return;
  // Taken with the learned probability of its side (technique_probabilities.h): the draw only
  // where it is below 1, so that other pixels keep their random numbers.
  const float q = v.probabilities.of(GuidingField::kNextEvent, d->ls.wi);
  if (q < 1 && rng.next_float() >= q) return;
  // The shadow ray before the MIS terms: an occluded light costs no densities (a coated
  // BSDF's are random walks). The same contributions are made.
  const Rgb tr = light_sample_visibility(scene, v.si, *d);  // through media too
  const bool occluded = tr.is_black();
  if (v.probabilities && guiding_.counts_techniques())
    guiding_.count_technique(GuidingField::kNextEvent, v.probabilities.leaf_toward(d->ls.wi),
                             !occluded);
  if (occluded) return;
  TechniqueTerms terms =
      terms_next_event(rules, *d->light, d->pmf, d->ls, v.si, v.bsdf, v.mis, v.guides);
  terms.own_factor = rules.mis(q);
  const float w = terms.weight(rules.counts());
  const Rgb value = v.beta * d->f * (d->ls.radiance * tr) * (w / (d->pmf * d->ls.pdf_w * q));
  if (value.is_black()) return;
  acc.add(false, 1, v.depth + 1, value, &terms);
}

void BidirIntegrator::connect_to_light_paths(const Scene& scene, const Iteration& it,
                                             const MisRules& rules, const CameraVertex& v,
                                             uint64_t light_path, Pcg32& rng, ScratchArena& arena,
                                             PixelAccumulator& acc) const {
  const uint64_t n = it.plan.light_paths;
  const int c = it.plan.connections_at(acc.pixel);
  if (n == 0 || c == 0 || rules.counts().connect == 0) return;
  const Rgb scaled = v.beta / float(c);
  for (int j = 0; j < c; ++j) {
    const uint64_t path =
        j == 0 ? light_path : std::min<uint64_t>(uint64_t(rng.next_float() * double(n)), n - 1);
    connect_to_light_path(scene, rules, v, scaled, path, j == 0, rng, arena, acc);
  }
}

void BidirIntegrator::connect_to_light_path(const Scene& scene, const MisRules& rules,
                                            const CameraVertex& cv, Rgb beta, uint64_t light_path,
                                            bool own, Pcg32& rng, ScratchArena& arena,
                                            PixelAccumulator& acc) const {
  const SurfaceInteraction& si = cv.si;
  const Bsdf& bsdf = cv.bsdf;
  const int depth = cv.depth;
  // A light vertex clearly behind a one-sided camera vertex gets f_camera = 0 below: rejected
  // before its interaction and BSDF are rebuilt. "Clearly": by more than the rounding between
  // the stored point and the rebuilt one, so that the rebuilt direction lies on the same side
  // and the connections made are exactly those made without this test.
  const float wo_side = dot(bsdf.shading().n, si.wo) < 0 ? -1.f : 1.f;
  const bool one_sided = bsdf.zero_across_surface();
  const float camera_extent = std::max({std::abs(si.p.x), std::abs(si.p.y), std::abs(si.p.z)});
  const uint32_t first = path_begin_[light_path], end = path_begin_[light_path + 1];
  if (own && !acc.own_path && end > first) {
    acc.own_path = static_cast<RebuiltLightVertex*>(
        arena.allocate(sizeof(RebuiltLightVertex) * (end - first), alignof(RebuiltLightVertex)));
    std::uninitialized_default_construct_n(acc.own_path, end - first);
  }
  RebuiltLightVertex scratch;    // a vertex of another light path, rebuilt for this connection
  CorrelationTrack light_track;  // correlation-aware MIS: a stored vertex's (load_track)
  for (uint32_t i = first; i < end; ++i) {
    const LightVertex& stored = vertices_[i];
    // Stored in increasing depth: once too long, all the rest are too.
    if (light_vertex_depth(stored) + depth > settings_.max_depth) break;
    const LightVertexData v = unpack_light_vertex(stored);
    if (one_sided) {
      const float margin =
          1e-4f *
          (1 + std::max({camera_extent, std::abs(v.p.x), std::abs(v.p.y), std::abs(v.p.z)}));
      if (wo_side * dot(bsdf.shading().n, v.p - si.p) < -margin) continue;
    }
    RebuiltLightVertex& rebuilt = own ? acc.own_path[i - first] : scratch;
    if (!own || !rebuilt.built) {
      rebuilt.si = scene.interaction_at(v.primitive, v.p, v.wo);
      rebuilt.bsdf = rebuilt.si.material->bsdf(rebuilt.si, arena);
      rebuilt.guides = guided_mis() && rebuilt.bsdf.valid()
                           ? guiding_.at(rebuilt.si.p, rebuilt.si.ng, rebuilt.bsdf)
                           : VertexGuides{};
      rebuilt.probabilities = tech_.guided ? guiding_.probabilities_at(rebuilt.si.p, rebuilt.si.ng)
                                           : VertexProbabilities{};
      rebuilt.built = true;
    }
    const SurfaceInteraction& light_si = rebuilt.si;
    const Bsdf& light_bsdf = rebuilt.bsdf;
    if (!light_bsdf.valid()) continue;
    const Vec3 d = light_si.p - si.p;
    const float dist2 = length_squared(d);
    if (!(dist2 > 0)) continue;
    const Vec3 dir = d / std::sqrt(dist2);
    // Taken with the light vertex's learned probability toward the camera vertex, decided
    // before the BSDFs are evaluated (a coated BSDF's f is a random walk).
    const VertexProbabilities& probabilities = rebuilt.probabilities;
    const float q = probabilities.of(GuidingField::kConnection, -dir);
    if (q < 1 && rng.next_float() >= q) continue;
    const Rgb f_camera = bsdf.f(si.wo, dir, TransportMode::Radiance) * bsdf.abs_cos(dir);
    if (f_camera.is_black()) continue;
    const Rgb f_light =
        light_bsdf.f(v.wo, -dir, TransportMode::Importance) * light_bsdf.abs_cos(dir);
    if (f_light.is_black()) continue;
    ++acc.work.connections;
    // The shadow ray before the MIS terms, as for next event estimation.
    const Rgb tr = scene.visibility(spawn_ray_between(si, light_si), si.medium_toward(dir),
                                    light_si.medium_toward(-dir));  // through media too
    const bool occluded = tr.is_black();
    if (probabilities && guiding_.counts_techniques())
      guiding_.count_technique(GuidingField::kConnection, probabilities.leaf_toward(-dir),
                               !occluded);
    if (occluded) continue;
    MisSums light_mis = v.mis;
    if (rules.correlated()) {
      load_track(i, &light_track);
      light_mis.corr = &light_track;
    }
    TechniqueTerms terms = terms_connection(rules, light_si, light_bsdf, v.wo, light_mis, si, bsdf,
                                            cv.mis, rebuilt.guides, cv.guides);
    terms.own_factor = rules.mis(q);
    const float w = terms.weight(rules.counts());
    const Rgb value = beta * v.throughput * tr * f_camera * f_light * (w / (dist2 * q));
    if (value.is_black()) continue;
    acc.add(false, v.depth + 1, depth + 1, value, &terms,
            own ? AdaptivePlan::Share::OwnLightPath : AdaptivePlan::Share::RandomLightPath);
  }
}

void BidirIntegrator::merge(const Scene& scene, const Iteration& it, const MisRules& rules,
                            const CameraVertex& cv, PixelAccumulator& acc) const {
  const SurfaceInteraction& si = cv.si;
  const Bsdf& bsdf = cv.bsdf;
  const int depth = cv.depth;
  ++acc.work.merge_queries;
  // The query photon mapping in this pixel would make (at the first non-delta scattering).
  const bool stop_query = !cv.mis.past_delta_chain;
  acc.work.stop_merge_queries += stop_query;
  const int max_depth = settings_.max_depth;
  const Scene::PrimitiveRange own_shape = scene.shape_primitives(si);
  const float max_off_plane = 0.5f * it.radius;
  CorrelationTrack light_track;  // correlation-aware MIS: a stored vertex's (load_track)
  grid_.for_each_near(
      si.p, vertices_,
      [&](uint32_t index, Vec3 q) {
        ++acc.work.photons;
        acc.work.stop_photons += stop_query;
        const LightVertex& stored = vertices_[index];
        const int light_depth = light_vertex_depth(stored);
        if (light_depth + depth - 1 > max_depth) return;
        if (std::abs(dot(q - si.p, si.ng)) > max_off_plane) return;
        LightVertexData v = unpack_light_vertex(stored);
        // The photon's throughput carries the flux through the surface (geometric cosine); the
        // camera vertex integrates with the shading cosine: |ns . wi| / |ng . wi|, as NEE and
        // connections have it through abs_cos (Veach 1997, section 5.3).
        const float cos_geometric = geometric_cos(si, v.wo);
        if (!(cos_geometric > 0)) return;
        const Rgb f =
            bsdf.f(si.wo, v.wo, TransportMode::Radiance) * (bsdf.abs_cos(v.wo) / cos_geometric);
        if (f.is_black()) return;
        if (!own_shape.contains(v.primitive) &&
            !photon_visible(scene, si, v.primitive, q, v.wo, it.radius))
          return;
        if (acc.stops) {  // a pixel no probe records: no terms needed
          acc.add(true, light_depth + 1, depth + 1,
                  cv.beta * f * v.throughput * it.merge_normalization);
          return;
        }
        if (rules.correlated()) {
          load_track(index, &light_track);
          v.mis.corr = &light_track;
        }
        const TechniqueTerms terms = terms_merge(rules, v.wo, v.mis, si, bsdf, cv.mis, cv.guides);
        const float w = tech_.unweighted ? 1.f : terms.weight(rules.counts());
        acc.add(true, light_depth + 1, depth + 1,
                cv.beta * f * v.throughput * (w * it.merge_normalization), &terms);
      },
      [&](uint32_t index, int stage) {
        if (!rules.correlated()) return;
        const StoredTrack& t = tracks_[index];
        if (stage == 0)
          __builtin_prefetch(&t);
        else if (t.count > StoredTrack::kInline)
          __builtin_prefetch(track_entries_.data() + t.first);
      });
}

bool BidirIntegrator::photon_visible(const Scene& scene, const SurfaceInteraction& si,
                                     uint32_t primitive, Vec3 q, Vec3 wo, float radius) const {
  const SurfaceInteraction photon = scene.interaction_at(primitive, q, wo);
  const float tolerance = 1e-4f * radius;
  const Vec3 n_query = face_forward(si.ng, wo), n_photon = face_forward(photon.ng, wo);
  if (dot(q - si.p, n_query) < -tolerance || dot(si.p - q, n_photon) < -tolerance) return false;
  const Vec3 origin = si.offset_origin(wo);
  const Vec3 target = photon.offset_origin(wo);
  return !scene.occluded({origin, target - origin, 1.f - 1e-6f});
}

}  // namespace caustica::bidir
