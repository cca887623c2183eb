#include "integrators/path_tracer.h"

#include "integrators/path_vertex.h"
#include "lights/light.h"
#include "lights/light_sampler.h"
#include "materials/material.h"
#include "scene/scene.h"

namespace caustica {

Rgb PathTracer::radiance(const Scene& scene, const Ray& camera_ray, Pcg32& rng,
                         ScratchArena& arena) const {
  const MisHeuristic heuristic = settings_.mis_or(MisHeuristic::Power);
  Rgb L(0.f), beta(1.f);
  Ray ray = camera_ray;
  int depth = 0;
  bool specular_bounce = false;
  float eta_scale = 1;  // product of eta^2 across refractions, undone for Russian roulette
  float prev_pdf = 0;   // solid-angle pdf of the BSDF sample that produced `ray`
  Vec3 prev_p;          // where that ray started (for the lights' pdf_li)
  SegmentEnd start;     // that ray's first end, for media (the camera's names none)

  // Emission seen by this ray: full weight after delta bounces, MIS-weighted otherwise.
  auto add_emission = [&](const SurfaceInteraction* hit) {
    add_emission_seen(scene, ray, hit, depth == 0 || specular_bounce, prev_pdf, prev_p, heuristic,
                      [&](Rgb Le, float w) { L += beta * Le * w; });
  };

  for (;;) {
    SurfaceInteraction si;
    Bsdf bsdf;
    if (!next_scattering_vertex(scene, ray, start, beta, arena, &si, &bsdf, add_emission)) break;
    if (depth++ == settings_.max_depth) break;

    const Vec3 wo = si.wo;
    // Next event estimation (skipped for delta BSDFs: a light sample can never be on the lobe;
    // the random numbers are drawn anyway to keep the stream aligned across vertex kinds).
    const float u_light = rng.next_float();
    const Vec2 u = rng.next_2d();
    L += direct_light_mis(
        scene, si, bsdf, beta, u_light, u,
        [&](Vec3 wi) { return bsdf.pdf(wo, wi, TransportMode::Radiance); },
        [&](float a, float b) { return mis_weight(heuristic, a, b); });

    const float uc = rng.next_float();
    const auto bs = bsdf.sample(wo, uc, rng.next_2d(), TransportMode::Radiance);
    if (!bs) break;
    beta *= bs->f * (bsdf.abs_cos(bs->wi) / bs->pdf);
    prev_pdf = bs->pdf_is_proportional ? bsdf.pdf(wo, bs->wi, TransportMode::Radiance) : bs->pdf;
    specular_bounce = bs->is_specular();
    if (bs->is_transmission()) eta_scale *= sqr(bs->eta);
    prev_p = si.p;
    start = si.medium_toward(bs->wi);
    ray = si.spawn_ray(bs->wi);
    if (beta.is_black()) break;
    if (!survives_russian_roulette(beta, eta_scale, depth, rng)) break;
  }
  return L;
}

}  // namespace caustica
