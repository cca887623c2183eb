// What every camera path does at its vertices, written once for pt, the bidirectional camera
// subpath and the integrators to come: the emitters a ray sees, the density with which next
// event estimation would have chosen them (emitter MIS), a light sample for next event
// estimation, and Russian roulette. Each integrator keeps its own weights; these give it the
// samples and pdfs.
#pragma once

#include <algorithm>
#include <optional>
#include <vector>

#include "core/math.h"
#include "core/rgb.h"
#include "core/rng.h"
#include "geometry/interaction.h"
#include "integrators/integrator.h"
#include "lights/light.h"
#include "lights/light_sampler.h"
#include "materials/bsdf.h"
#include "materials/material.h"
#include "scene/scene.h"

namespace caustica {

// The emitters a camera ray reaches: with hit == nullptr (the ray escaped) every infinite light
// along ray.d, else the area light of the hit primitive. fn(const Light&, Rgb Le) for each
// non-black one.
template <typename Fn>
void for_each_emitter_seen(const std::vector<const Light*>& infinite_lights, const Ray& ray,
                           const SurfaceInteraction* hit, Fn&& fn) {
  if (!hit) {
    for (const Light* light : infinite_lights) {
      const Rgb Le = light->radiance_escaped(ray.d);
      if (!Le.is_black()) fn(*light, Le);
    }
  } else if (hit->area_light) {
    const Rgb Le = hit->area_light->radiance(hit->p, hit->ng, hit->uv, hit->wo);
    if (!Le.is_black()) fn(*hit->area_light, Le);
  }
}

// Solid-angle density at prev_p with which next event estimation (the one light distribution
// times the light's pdf_li) picks the emitter seen along dir: at `hit`, or, with hit ==
// nullptr, the infinite light in that direction.
float next_event_pdf(const LightSampler& lights, const Light& light, Vec3 prev_p, Vec3 dir,
                     const SurfaceInteraction* hit);

// The MIS heuristic of the camera-path integrators for two densities (power by default).
inline float mis_weight(MisHeuristic heuristic, float pdf_a, float pdf_b) {
  return heuristic == MisHeuristic::Power ? power_heuristic(pdf_a, pdf_b)
                                          : balance_heuristic(pdf_a, pdf_b);
}

// Emission seen along a sampled ray (at `hit`, or the infinite lights with hit == nullptr),
// handed to add(Rgb Le, float weight): weight 1 for the camera ray and after a delta bounce (no
// light sample could have found it), else the MIS weight against next event estimation from
// prev_p, the ray having been sampled with density prev_pdf. nee_probability: the probability
// with which prev_p ran next event estimation at all (direct_light_mis's `probability`).
template <typename Add>
void add_emission_seen(const Scene& scene, const Ray& ray, const SurfaceInteraction* hit,
                       bool full_weight, float prev_pdf, Vec3 prev_p, MisHeuristic heuristic,
                       Add&& add, float nee_probability = 1) {
  for_each_emitter_seen(scene.infinite_lights(), ray, hit, [&](const Light& light, Rgb Le) {
    if (full_weight) {
      add(Le, 1.f);
      return;
    }
    const float light_pdf =
        nee_probability * next_event_pdf(scene.light_sampler(), light, prev_p, ray.d, hit);
    add(Le, mis_weight(heuristic, prev_pdf, light_pdf));
  });
}

// A light sample for next event estimation from si: the light picked by the power-based light
// distribution (pmf), the point sampled on it (ls), the BSDF value times |cos| toward it (f) and
// the shadow ray to test. Nothing if any factor vanishes; no ray is traced. u_light picks the
// light and u the point (the caller draws them, in that order).
struct DirectLightSample {
  const Light* light = nullptr;
  float pmf = 0;
  LightLiSample ls;
  Rgb f;
  Ray shadow;
};
std::optional<DirectLightSample> sample_direct_light(const Scene& scene,
                                                     const SurfaceInteraction& si, const Bsdf& bsdf,
                                                     float u_light, Vec2 u);

// Follows `ray` to the next vertex that scatters: through interfaces (no material, or a material
// with no BSDF there) it goes straight on. Each segment's transmittance through absorbing media
// (geometry/medium.h) is multiplied into beta before the surface it reaches is seen; `start` is
// the segment's first end (the camera's, {}, or the previous vertex's medium_toward(ray.d)), and
// ray.d is a unit vector, so that si->t is the segment's length.
// on_emission(hit) is called for every surface reached (hit != nullptr) and, with nullptr, when
// the ray escapes; then it returns false. On true, si and bsdf describe the vertex (bsdf
// allocated in arena).
template <typename OnEmission>
bool next_scattering_vertex(const Scene& scene, Ray& ray, SegmentEnd start, Rgb& beta,
                            ScratchArena& arena, SurfaceInteraction* si, Bsdf* bsdf,
                            OnEmission&& on_emission) {
  const bool media = scene.has_media();
  for (;;) {
    if (!scene.intersect(ray, si)) {
      if (media) beta *= scene.transmittance(start, {}, kInfinity);
      on_emission(nullptr);
      return false;
    }
    if (media) beta *= scene.transmittance(start, si->medium_toward(-ray.d), si->t);
    on_emission(si);
    if (si->material) {
      *bsdf = si->material->bsdf(*si, arena);
      if (bsdf->valid()) return true;
    }
    start = si->medium_toward(ray.d);
    ray = si->spawn_ray(ray.d);
  }
}

// What of the light sample's radiance reaches si: 0 where its shadow ray is blocked, else the
// transmittance of any absorbing media on the way (Scene::visibility, geometry/medium.h).
inline Rgb light_sample_visibility(const Scene& scene, const SurfaceInteraction& si,
                                   const DirectLightSample& d) {
  return scene.visibility(d.shadow, si.medium_toward(d.ls.wi),
                          d.light->medium_toward(d.ls.n_light, -d.ls.wi));
}

// What an unoccluded next event sample saw, for integrators that learn from it (path guiding):
// the direction, the radiance arriving along it, f |cos| toward it, the density of the light
// sample (for a delta light its selection probability) and the MIS weight.
struct NextEventSeen {
  Vec3 wi;
  Rgb Li, f;
  float light_pdf = 0, weight = 0;
  bool delta_light = false;
};

// Next event estimation with MIS against BSDF-side sampling, as unidirectional camera paths do
// it: beta * f * Le * w / p_light for an unoccluded light sample, else black (also for delta
// BSDFs and light-less scenes). sampling_pdf(wi) is the solid-angle density with which the
// path's own direction sampling would pick wi; mis(p_light, p_sampling) the heuristic; delta
// lights get weight 1. With `seen`, an unoccluded sample is also described there (else
// seen->Li is black). probability: the probability with which the caller runs next event
// estimation at this vertex (guided-pt's learned one, guided_path_tracer.cpp); it scales the
// light sample's density, so the estimate stays unbiased and, with add_emission_seen's
// nee_probability, the MIS weights still sum to one.
template <typename SamplingPdf, typename Mis>
Rgb direct_light_mis(const Scene& scene, const SurfaceInteraction& si, const Bsdf& bsdf, Rgb beta,
                     float u_light, Vec2 u, SamplingPdf&& sampling_pdf, Mis&& mis,
                     NextEventSeen* seen = nullptr, float probability = 1) {
  if (seen) seen->Li = Rgb(0.f);
  if (bsdf.is_delta() || scene.light_sampler().empty()) return Rgb(0.f);
  const auto d = sample_direct_light(scene, si, bsdf, u_light, u);
  if (!d) return Rgb(0.f);
  const Rgb tr = light_sample_visibility(scene, si, *d);
  if (tr.is_black()) return Rgb(0.f);
  const float light_pdf = probability * (d->pmf * d->ls.pdf_w);
  const float w = d->light->is_delta() ? 1.f : mis(light_pdf, sampling_pdf(d->ls.wi));
  if (seen) *seen = {d->ls.wi, d->ls.radiance * tr, d->f, light_pdf, w, d->light->is_delta()};
  return beta * d->f * (d->ls.radiance * tr) * (w / light_pdf);
}

// The probability q that Russian roulette ends a path after `depth` scattering vertices with
// throughput beta: from the throughput with the radiance scaling of refraction (eta_scale)
// removed, never before the second vertex; 0 means no roulette.
inline float russian_roulette_end(Rgb beta, float eta_scale, int depth) {
  const float rr = (beta * eta_scale).max_component();
  return rr < 1 && depth > 1 ? std::max(0.f, 1 - rr) : 0.f;
}

// Russian roulette (russian_roulette_end). Returns false when the path ends; otherwise beta is
// divided by the survival probability.
inline bool survives_russian_roulette(Rgb& beta, float eta_scale, int depth, Pcg32& rng) {
  const float q = russian_roulette_end(beta, eta_scale, depth);
  if (q > 0) {
    if (rng.next_float() < q) return false;
    beta = beta / (1 - q);
  }
  return true;
}

// Roulette for guided sampling, on the larger of the throughput and the one BSDF sampling alone
// would have had (rr_beta): a guided direction toward bright light has a small weight (its
// density is high) and must not be ended for it, nor a path whose weight grew. Any survival
// probability that depends only on the path so far keeps the estimate unbiased. Returns false
// when the path ends; else both throughputs are divided by the survival probability.
inline bool survives_guided_roulette(Rgb& beta, Rgb& rr_beta, float eta_scale, int depth,
                                     Pcg32& rng) {
  const Rgb larger(std::max(beta.r, rr_beta.r), std::max(beta.g, rr_beta.g),
                   std::max(beta.b, rr_beta.b));
  const float q = russian_roulette_end(larger, eta_scale, depth);
  if (q > 0) {
    if (rng.next_float() < q) return false;
    beta = beta / (1 - q);
    rr_beta = rr_beta / (1 - q);
  }
  return true;
}

}  // namespace caustica
