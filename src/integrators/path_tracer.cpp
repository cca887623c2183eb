#include "integrators/path_tracer.h"

#include "lights/light.h"
#include "lights/light_sampler.h"
#include "materials/material.h"
#include "film/film.h"
#include "film/tiles.h"
#include "scene/scene.h"

namespace caustica {

float PathTracer::mis_weight(float pdf_a, float pdf_b) const {
  return settings_.mis == MisHeuristic::Power ? power_heuristic(pdf_a, pdf_b) : balance_heuristic(pdf_a, pdf_b);
}

void PathTracer::prepare(const Scene& scene, Film&) {
  filter_ = PixelFilter(scene.camera().pixel_filter());
}

void PathTracer::render_iteration(const Scene& scene, uint32_t iteration, Film& film) {
  const Camera& camera = scene.camera();
  parallel_for_tiles(film.width(), film.height(), [&](const Tile& tile, ScratchArena& arena) {
    for (int y = tile.y0; y < tile.y1; ++y)
      for (int x = tile.x0; x < tile.x1; ++x) {
        const uint64_t pixel = uint64_t(y) * film.width() + x;
        Pcg32 rng = Pcg32::for_sample(pixel, iteration, settings_.seed);
        // Filter importance sampling (pixel_filter.h): the sample's weight is 1 for a positive
        // filter and carries the sign of negative lobes.
        const CameraFilterSample fs = filter_.sample_camera(x, y, rng.next_2d());
        const Vec2 lens = rng.next_2d();
        const Ray ray = camera.generate_ray(fs.raster, lens);
        arena.reset();
        film.add_sample(x, y, radiance(scene, ray, rng, arena) * fs.weight);
      }
  });
}

Rgb PathTracer::radiance(const Scene& scene, const Ray& camera_ray, Pcg32& rng, ScratchArena& arena) const {
  const LightSampler& lights = scene.light_sampler();
  Rgb L(0.f), beta(1.f);
  Ray ray = camera_ray;
  int depth = 0;
  bool specular_bounce = false;
  float eta_scale = 1;  // product of eta^2 across refractions, undone for Russian roulette
  float prev_pdf = 0;   // solid-angle pdf of the BSDF sample that produced `ray`
  Vec3 prev_p;          // where that ray started (for the lights' pdf_li)

  for (;;) {
    SurfaceInteraction si;
    if (!scene.intersect(ray, &si)) {
      for (const Light* light : scene.infinite_lights()) {
        const Rgb Le = light->radiance_escaped(ray.d);
        if (Le.is_black()) continue;
        if (depth == 0 || specular_bounce) {
          L += beta * Le;
        } else {
          const float light_pdf = lights.pmf(light) * light->pdf_li(prev_p, ray.d, {}, {});
          L += beta * Le * mis_weight(prev_pdf, light_pdf);
        }
      }
      break;
    }

    // Emission seen by this ray: full weight after delta bounces, MIS-weighted otherwise.
    if (si.area_light) {
      const Rgb Le = si.area_light->radiance(si.p, si.ng, si.uv, si.wo);
      if (!Le.is_black()) {
        if (depth == 0 || specular_bounce) {
          L += beta * Le;
        } else {
          const float light_pdf = lights.pmf(si.area_light) * si.area_light->pdf_li(prev_p, ray.d, si.p, si.ng);
          L += beta * Le * mis_weight(prev_pdf, light_pdf);
        }
      }
    }

    if (!si.material) {  // an interface without scattering: continue straight through
      ray = si.spawn_ray(ray.d);
      continue;
    }
    const Bsdf bsdf = si.material->bsdf(si, arena);
    if (!bsdf.valid()) {
      ray = si.spawn_ray(ray.d);
      continue;
    }
    if (depth++ == settings_.max_depth) break;

    const Vec3 wo = si.wo;
    // Next event estimation (skipped for delta BSDFs: a light sample can never be on the lobe).
    if (!bsdf.is_delta() && !lights.empty()) {
      float pmf;
      const Light* light = lights.sample(rng.next_float(), &pmf);
      const Vec2 u = rng.next_2d();
      if (light) {
        const auto ls = light->sample_li(si.p, u);
        if (ls && ls->pdf_w > 0 && !ls->radiance.is_black()) {
          const Rgb f = bsdf.f(wo, ls->wi, TransportMode::Radiance) * bsdf.abs_cos(ls->wi);
          if (!f.is_black()) {
            const Ray shadow = std::isinf(ls->distance) ? si.spawn_ray(ls->wi) : si.spawn_ray_to(ls->p_light);
            if (!scene.occluded(shadow)) {
              const float light_pdf = pmf * ls->pdf_w;
              const float w = light->is_delta() ? 1.f : mis_weight(light_pdf, bsdf.pdf(wo, ls->wi, TransportMode::Radiance));
              L += beta * f * ls->radiance * (w / light_pdf);
            }
          }
        }
      }
    } else {
      rng.next_float();  // keep the random stream aligned across vertex kinds
      rng.next_2d();
    }

    const float uc = rng.next_float();
    const auto bs = bsdf.sample(wo, uc, rng.next_2d(), TransportMode::Radiance);
    if (!bs) break;
    beta *= bs->f * (bsdf.abs_cos(bs->wi) / bs->pdf);
    prev_pdf = bs->pdf_is_proportional ? bsdf.pdf(wo, bs->wi, TransportMode::Radiance) : bs->pdf;
    specular_bounce = bs->is_specular();
    if (bs->is_transmission()) eta_scale *= sqr(bs->eta);
    prev_p = si.p;
    ray = si.spawn_ray(bs->wi);
    if (beta.is_black()) break;

    // Russian roulette on the throughput with radiance scaling by refraction removed.
    const float rr = (beta * eta_scale).max_component();
    if (rr < 1 && depth > 1) {
      const float q = std::max(0.f, 1 - rr);
      if (rng.next_float() < q) break;
      beta = beta / (1 - q);
    }
  }
  return L;
}

}  // namespace caustica
