#include "integrators/path_vertex.h"

#include <cmath>

#include "lights/light_sampler.h"
#include "scene/scene.h"

namespace caustica {

float next_event_pdf(const LightSampler& lights, const Light& light, Vec3 prev_p, Vec3 dir,
                     const SurfaceInteraction* hit) {
  return hit ? lights.pmf(&light) * light.pdf_li(prev_p, dir, hit->p, hit->ng)
             : lights.pmf(&light) * light.pdf_li(prev_p, dir, {}, {});
}

std::optional<DirectLightSample> sample_direct_light(const Scene& scene,
                                                     const SurfaceInteraction& si, const Bsdf& bsdf,
                                                     float u_light, Vec2 u) {
  DirectLightSample d;
  d.light = scene.light_sampler().sample(u_light, &d.pmf);
  if (!d.light || !(d.pmf > 0)) return std::nullopt;
  const auto ls = d.light->sample_li(si.p, u);
  if (!ls || !(ls->pdf_w > 0) || ls->radiance.is_black()) return std::nullopt;
  d.ls = *ls;
  d.f = bsdf.f(si.wo, ls->wi, TransportMode::Radiance) * bsdf.abs_cos(ls->wi);
  if (d.f.is_black()) return std::nullopt;
  d.shadow = std::isinf(ls->distance) ? si.spawn_ray(ls->wi) : si.spawn_ray_to(ls->p_light);
  return d;
}

}  // namespace caustica
